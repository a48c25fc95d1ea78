#include "cosmology/Background.hpp"

#include <fmt/format.h>

#include <array>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/numeric/odeint.hpp>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/Error.hpp"

namespace fountain::cosmology {

namespace {

// Adaptive 15-point Gauss-Kronrod to 1e-12 relative (a tighter request only meets round-off).
template <class F>
double integrate(F&& f, double lo, double hi) {
  return boost::math::quadrature::gauss_kronrod<double, 15>::integrate(f, lo, hi, 15, 1e-12);
}

}  // namespace

Background::Background(const CosmologyParams& p, double hubble0) : p_(p), h0_(hubble0) {
  if (!(p.omega_m > 0.0) || !(p.omega_lambda >= 0.0) || !std::isfinite(p.omega_m) || !std::isfinite(p.omega_lambda) ||
      !(hubble0 > 0.0))
    throw InputError(fmt::format("cosmology: omega_m = {} must be positive and omega_lambda = {} not negative",
                                 p.omega_m, p.omega_lambda));
  if (const double limit = expansion_limit(); !(limit > 1.0))
    throw InputError(fmt::format("cosmology: omega_m = {} with omega_lambda = {} (Omega_k = {}) stops expanding at "
                                 "a = {:.6g}, before today (a = 1)",
                                 p.omega_m, p.omega_lambda, p.omega_k(), limit));
}

double Background::expansion_limit() const {
  // a^3 E^2 = Omega_m + Omega_k a + Omega_Lambda a^3 is positive at a = 0; with Omega_Lambda
  // >= 0 it can only reach zero while falling, i.e. with Omega_k < 0, before its minimum.
  const double om = p_.omega_m, ok = p_.omega_k(), ol = p_.omega_lambda;
  if (ok >= 0.0) return std::numeric_limits<double>::infinity();
  if (ol == 0.0) return om / -ok;
  const double a_min = std::sqrt(-ok / (3.0 * ol));
  auto f = [&](double a) { return om + ok * a + ol * a * a * a; };
  if (f(a_min) > 0.0) return std::numeric_limits<double>::infinity();
  double lo = 0.0, hi = a_min;  // f(lo) > 0 >= f(hi)
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) > 0.0 ? lo : hi) = mid;
  }
  return hi;
}

double Background::E(double a) const {
  return std::sqrt(p_.omega_m / (a * a * a) + p_.omega_k() / (a * a) + p_.omega_lambda);
}

double Background::dln_e_dln_a(double a) const {
  const double e = E(a);
  return -(3.0 * p_.omega_m / (a * a * a) + 2.0 * p_.omega_k() / (a * a)) / (2.0 * e * e);
}

double Background::omega_m_at(double a) const {
  const double e = E(a);
  return p_.omega_m / (a * a * a * e * e);
}

double Background::cosmic_time(double a) const {
  // In x = a^(3/2) the integrand stays finite at a = 0: dt = (2/3) dx / (x H).
  const double x_end = a * std::sqrt(a);
  auto f = [this](double x) {
    if (x <= 0.0) return 2.0 / (3.0 * h0_ * std::sqrt(p_.omega_m));
    return 2.0 / (3.0 * x * hubble(std::cbrt(x * x)));
  };
  return integrate(f, 0.0, x_end);
}

double Background::growth(double a) const {
  // D = (5 Omega_m / 2) E(a) int_0^a da' / (a' E(a'))^3; the integrand vanishes as a'^(3/2).
  auto f = [this](double b) {
    if (b <= 0.0) return 0.0;
    const double be = b * E(b);
    return 1.0 / (be * be * be);
  };
  return 2.5 * p_.omega_m * E(a) * integrate(f, 0.0, a);
}

double Background::growth_rate(double a) const {
  const double e = E(a);
  return (2.5 * p_.omega_m / (a * a * growth(a)) - 1.5 * p_.omega_m / (a * a * a) - p_.omega_k() / (a * a)) / (e * e);
}

SecondOrderGrowth Background::second_order_growth(double a) const {
  // D'' + (2 + dlnE/ds) D' = (3/2) Omega_m(a) D and the same for D2 with the source
  // -(3/2) Omega_m(a) D^2, in s = ln a, from a = 1e-4 where the growing modes are exact.
  using State = std::array<double, 4>;  // D, dD/ds, D2, dD2/ds
  const double a0 = 1e-4;
  State y{a0, a0, -3.0 / 7.0 * a0 * a0, -6.0 / 7.0 * a0 * a0};
  if (a <= a0) return {-3.0 / 7.0 * a * a, 2.0};
  auto rhs = [this](const State& s, State& ds, double lna) {
    const double b = std::exp(lna);
    const double friction = 2.0 + dln_e_dln_a(b);
    const double source = 1.5 * omega_m_at(b);
    ds[0] = s[1];
    ds[1] = -friction * s[1] + source * s[0];
    ds[2] = s[3];
    ds[3] = -friction * s[3] + source * (s[2] - s[0] * s[0]);
  };
  namespace ode = boost::numeric::odeint;
  ode::integrate_adaptive(ode::make_controlled<ode::runge_kutta_dopri5<State>>(1e-14, 1e-13), rhs, y, std::log(a0),
                          std::log(a), 1e-3);
  return {y[2], y[3] / y[2]};
}

double initial_gas_temperature(const CosmologyParams& c, double a) {
  const double omega_b_h2 = c.omega_b * c.hubble_param * c.hubble_param;
  const double a_dec = 1.0 / (160.0 * std::pow(omega_b_h2 / 0.022, 0.4));
  return a < a_dec ? kCmbTemperature / a : kCmbTemperature * a_dec / (a * a);
}

double hubble0_in(const Units& units) {
  const Units mpc_msun_kms;  // the defaults
  return kHubbleInternal * (units.length_cgs / mpc_msun_kms.length_cgs) / (units.velocity_cgs / mpc_msun_kms.velocity_cgs);
}

double critical_density0_in(const Units& units) {
  const double h0 = hubble0_in(units);
  return 3.0 * h0 * h0 / (8.0 * std::numbers::pi * units.gravitational_constant());
}

}  // namespace fountain::cosmology
