#include "cooling/RadiativeCooling.hpp"

#include <cmath>

namespace fountain::cooling {

namespace {
constexpr double k_boltzmann = 1.380649e-16;  // erg/K
constexpr double m_proton = 1.67262192e-24;   // g
}  // namespace

RadiativeCooling::RadiativeCooling(const CoolingTable& table, const Units& units, double hydrogen_fraction)
    : table_(table), units_(units), x_h_(hydrogen_fraction) {
  u_floor_ = energy_at(std::pow(10.0, CoolingTable::log_t_min));
}

double RadiativeCooling::energy_at(double t) const {
  const double log_t = std::log10(t);
  const double u_cgs = 1.5 * k_boltzmann * t / table_.mean_particle_mass_g(log_t);
  return u_cgs / units_.specific_energy_cgs();
}

double RadiativeCooling::temperature(double u) const {
  const double t_min = std::pow(10.0, CoolingTable::log_t_min), t_max = std::pow(10.0, CoolingTable::log_t_max);
  // Outside the table the mean particle mass is held at its end values, so u is linear in T.
  if (u <= u_floor_) return t_min * u / u_floor_;
  const double u_max = energy_at(t_max);
  if (u >= u_max) return t_max * u / u_max;
  double lo = CoolingTable::log_t_min, hi = CoolingTable::log_t_max;
  for (int it = 0; it < 50; ++it) {
    const double mid = 0.5 * (lo + hi);
    (energy_at(std::pow(10.0, mid)) < u ? lo : hi) = mid;
  }
  return std::pow(10.0, 0.5 * (lo + hi));
}

double RadiativeCooling::du_dt(double rho, double u) const {
  if (u <= u_floor_) return 0.0;
  const double log_t = std::log10(temperature(u));
  const double rho_cgs = rho * units_.density_cgs();
  const double n_h = x_h_ * rho_cgs / m_proton;
  const double n_e = table_.electrons_per_h(log_t) * n_h;
  const double n_t = table_.ions_per_h(log_t) * n_h;
  const double rate_cgs = -std::pow(10.0, table_.log_lambda_norm(log_t)) * n_e * n_t / rho_cgs;  // erg/g/s
  return rate_cgs * units_.time_cgs() / units_.specific_energy_cgs();
}

double RadiativeCooling::implicit_step(double rho, double u_old, double du_dt_hydro, double dt) const {
  const double u_free = u_old + dt * du_dt_hydro;
  if (u_free <= u_floor_ || dt <= 0.0) return u_free;
  // g(u) = u - u_free - dt du_dt(u): g(u_floor) < 0 <= g(u_free). Bisection in log u.
  double lo = std::log(u_floor_), hi = std::log(u_free);
  if (du_dt(rho, u_free) == 0.0) return u_free;
  for (int it = 0; it < 80 && hi - lo > 1e-14; ++it) {
    const double mid = 0.5 * (lo + hi);
    const double u = std::exp(mid);
    (u - u_free - dt * du_dt(rho, u) < 0.0 ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

}  // namespace fountain::cooling
