#include "cosmology/PowerSpectrum.hpp"

#include <cmath>
#include <numbers>

namespace fountain::cosmology {

namespace {
double top_hat(double y) {
  if (y < 1e-4) return 1.0 - y * y / 10.0;  // the series: 3 (sin y - y cos y) / y^3 loses digits near 0
  return 3.0 * (std::sin(y) - y * std::cos(y)) / (y * y * y);
}
}  // namespace

double top_hat_variance(const std::function<double(double)>& power, double radius) {
  const double ln_lo = std::log(1e-6), ln_hi = std::log(1e5);
  const int intervals = 2 * static_cast<int>(std::ceil(32.0 * (ln_hi - ln_lo)));  // even, 64 per e-fold
  const double step = (ln_hi - ln_lo) / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double k = std::exp(ln_lo + i * step);
    const double w = top_hat(k * radius);
    const double f = k * k * k * power(k) * w * w;  // dk = k dln k
    sum += f * (i == 0 || i == intervals ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0));
  }
  return sum * step / 3.0 / (2.0 * std::numbers::pi * std::numbers::pi);
}

LinearPowerSpectrum::LinearPowerSpectrum(const EisensteinHu& transfer, double n_s, double sigma_8)
    : transfer_(transfer), n_s_(n_s) {
  amplitude_ = 1.0;
  amplitude_ = sigma_8 * sigma_8 / top_hat_variance([this](double k) { return (*this)(k); }, 8.0);
}

double LinearPowerSpectrum::operator()(double k) const {
  if (!(k > 0.0)) return 0.0;
  const double t = transfer_(k);
  return amplitude_ * std::pow(k, n_s_) * t * t;
}

double LinearPowerSpectrum::sigma(double radius) const {
  return std::sqrt(top_hat_variance([this](double k) { return (*this)(k); }, radius));
}

}  // namespace fountain::cosmology
