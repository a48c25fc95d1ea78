#include "cooling/RadiativeCooling.hpp"

#include <algorithm>
#include <cmath>

namespace fountain::cooling {

namespace {
constexpr double k_boltzmann = 1.380649e-16;  // erg/K
constexpr double m_proton = 1.67262192e-24;   // g
constexpr double kNodeStep = 0.05;             // the tables' spacing in log T
double node_log_t(int k) { return CoolingTable::log_t_min + kNodeStep * k; }

// Root of f on [lo, hi] with f(lo) <= 0 <= f(hi), by regula falsi with the Illinois
// modification: superlinear on smooth f, and never leaves the bracket.
template <class F>
double bracketed_root(F&& f, double lo, double hi, double f_lo, double f_hi, double tolerance) {
  int side = 0;
  for (int it = 0; it < 100 && hi - lo > tolerance; ++it) {
    double x = f_hi != f_lo ? lo - f_lo * (hi - lo) / (f_hi - f_lo) : 0.5 * (lo + hi);
    if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
    const double fx = f(x);
    if (fx == 0.0) return x;
    if (fx < 0.0) {
      lo = x, f_lo = fx;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = x, f_hi = fx;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  return 0.5 * (lo + hi);
}
}  // namespace

RadiativeCooling::RadiativeCooling(const CoolingTable& table, const Units& units, double hydrogen_fraction)
    : table_(table), units_(units), x_h_(hydrogen_fraction) {
  u_floor_ = energy_at(std::pow(10.0, CoolingTable::log_t_min));
  u_max_ = energy_at(std::pow(10.0, CoolingTable::log_t_max));
  const int nodes = static_cast<int>(std::lround((CoolingTable::log_t_max - CoolingTable::log_t_min) / kNodeStep)) + 1;
  for (int k = 0; k < nodes; ++k) log_u_nodes_.push_back(std::log(energy_at(std::pow(10.0, node_log_t(k)))));
}

double RadiativeCooling::energy_at(double t) const {
  const double log_t = std::log10(t);
  const double u_cgs = 1.5 * k_boltzmann * t / table_.mean_particle_mass_g(log_t);
  return u_cgs / units_.specific_energy_cgs();
}

double RadiativeCooling::log10_temperature(double u) const {
  // Outside the table the mean particle mass is held at its end values, so u is linear in T.
  if (u <= u_floor_) return CoolingTable::log_t_min + std::log10(u / u_floor_);
  if (u >= u_max_) return CoolingTable::log_t_max + std::log10(u / u_max_);
  // u(T) is monotonic: find the table interval holding u, then solve inside it. There the
  // mean particle mass is linear in x = log10 T, so ln u(x) = c + x ln 10 - ln mu(x) is smooth
  // and nearly linear: Newton from the linear guess converges in a few steps.
  const double log_u = std::log(u);
  const auto it = std::upper_bound(log_u_nodes_.begin(), log_u_nodes_.end(), log_u);
  const int k = std::clamp(static_cast<int>(it - log_u_nodes_.begin()) - 1, 0, static_cast<int>(log_u_nodes_.size()) - 2);
  const double x_lo = node_log_t(k), x_hi = node_log_t(k + 1);
  const double mu_lo = table_.mean_particle_mass_g(x_lo), mu_slope = (table_.mean_particle_mass_g(x_hi) - mu_lo) / kNodeStep;
  const double ln10 = std::log(10.0);
  const double c = log_u_nodes_[k] - x_lo * ln10 + std::log(mu_lo);  // ln u = c + x ln10 - ln mu(x)
  double x = x_lo + kNodeStep * (log_u - log_u_nodes_[k]) / (log_u_nodes_[k + 1] - log_u_nodes_[k]);
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double mu = mu_lo + (x - x_lo) * mu_slope;
    const double g = c + x * ln10 - std::log(mu) - log_u;
    const double step = g / (ln10 - mu_slope / mu);
    x = std::clamp(x - step, x_lo, x_hi);
    if (std::fabs(step) < 1e-14) break;
  }
  return x;
}

double RadiativeCooling::temperature(double u) const { return std::pow(10.0, log10_temperature(u)); }

double RadiativeCooling::du_dt(double rho, double u) const {
  if (u <= u_floor_) return 0.0;
  const double log_t = log10_temperature(u);
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
  if (du_dt(rho, u_free) == 0.0) return u_free;
  // g(u) = u - u_free - dt du_dt(u): g(u_floor) < 0 <= g(u_free); solved in log u.
  auto g = [&](double log_u) {
    const double u = std::exp(log_u);
    return u - u_free - dt * du_dt(rho, u);
  };
  const double lo = std::log(u_floor_), hi = std::log(u_free);
  return std::exp(bracketed_root(g, lo, hi, g(lo), g(hi), 1e-13));
}

}  // namespace fountain::cooling
