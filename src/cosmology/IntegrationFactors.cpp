#include "cosmology/IntegrationFactors.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>

#include "core/Error.hpp"

namespace fountain::cosmology {

IntegrationFactors::IntegrationFactors(const Background& background, double gamma, double a_begin, double a_end,
                                       int intervals)
    : background_(background), gamma_(gamma), a_begin_(a_begin), a_end_(a_end) {
  if (!(a_begin > 0.0 && a_end > a_begin) || intervals < 1)
    throw InputError(fmt::format("cosmology: the run must go from a_begin = {} > 0 to a larger a_end = {}", a_begin,
                                 a_end));
  if (const double limit = background.expansion_limit(); !(a_end < limit))
    throw InputError(fmt::format("cosmology: omega_m = {} with omega_lambda = {} stops expanding at a = {:.6g}, "
                                 "before a_end = {}",
                                 background.params().omega_m, background.params().omega_lambda, limit, a_end));
  ln_begin_ = std::log(a_begin);
  step_ = (std::log(a_end) - ln_begin_) / intervals;
  for (int k = 0; k < 4; ++k) {
    const Kind kind = static_cast<Kind>(k);
    auto& t = table_[static_cast<std::size_t>(k)];
    t.assign(static_cast<std::size_t>(intervals) + 1, 0.0);
    auto& m = node_slope_[static_cast<std::size_t>(k)];
    m.resize(static_cast<std::size_t>(intervals) + 1);
    for (int i = 0; i <= intervals; ++i) m[static_cast<std::size_t>(i)] = slope(kind, std::exp(ln_begin_ + i * step_)) * step_;
    auto f = [&](double lna) { return slope(kind, std::exp(lna)); };
    for (int i = 0; i < intervals; ++i) {
      const double lo = ln_begin_ + i * step_, hi = ln_begin_ + (i + 1) * step_;
      t[static_cast<std::size_t>(i) + 1] =
          t[static_cast<std::size_t>(i)] +
          boost::math::quadrature::gauss_kronrod<double, 15>::integrate(f, lo, hi, 8, 1e-12);
    }
  }
}

double IntegrationFactors::slope(Kind k, double a) const {
  const double h = background_.hubble(a);
  switch (k) {
    case drift: return 1.0 / (a * a * h);
    case gravity_kick: return 1.0 / (a * h);
    case hydro_kick: return 1.0 / (std::pow(a, 3.0 * gamma_ - 3.0) * h);
    case time: return 1.0 / h;
  }
  return 0.0;
}

double IntegrationFactors::cumulative(Kind k, double a) const { return cumulative_at_ln(k, std::log(a)); }

double IntegrationFactors::cumulative_at_ln(Kind k, double ln_a) const {
  const auto& t = table_[static_cast<std::size_t>(k)];
  const double x = (ln_a - ln_begin_) / step_;
  const int last = static_cast<int>(t.size()) - 2;
  const int i = std::clamp(static_cast<int>(std::floor(x)), 0, last);
  const double s = x - i;
  // Cubic Hermite on [i, i + 1] with the exact slopes at the nodes (per unit of x, so times step_).
  const auto& m = node_slope_[static_cast<std::size_t>(k)];
  const double m0 = m[static_cast<std::size_t>(i)], m1 = m[static_cast<std::size_t>(i) + 1];
  const double p0 = t[static_cast<std::size_t>(i)], p1 = t[static_cast<std::size_t>(i) + 1];
  const double s2 = s * s, s3 = s2 * s;
  return (2.0 * s3 - 3.0 * s2 + 1.0) * p0 + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * p1 +
         (s3 - s2) * m1;
}

double IntegrationFactors::scale_factor_after(double t) const {
  // F_time increases with slope 1/H in ln a. Newton overshoots from the early, fast-expanding
  // end, so its steps are kept inside a bracket and replaced by halving when they leave it.
  const double ln_end = std::log(a_end_);
  if (!(t >= 0.0 && t <= cumulative(time, a_end_)))
    throw InputError(fmt::format("cosmology: the time {} after a_begin lies outside the run (a_begin = {}, a_end = {})",
                                 t, a_begin_, a_end_));
  double lo = ln_begin_, hi = ln_end, lna = 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    const double a = std::exp(lna);
    const double f = cumulative(time, a) - t;
    (f < 0.0 ? lo : hi) = lna;
    double next = lna - f * background_.hubble(a);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool settled = std::fabs(next - lna) <= 1e-15 * std::max(1.0, std::fabs(lna)) || hi - lo <= 1e-15;
    lna = next;
    if (settled) return std::exp(lna);
  }
  throw InputError(fmt::format("cosmology: no scale factor found for the time {} after a_begin", t));
}

}  // namespace fountain::cosmology
