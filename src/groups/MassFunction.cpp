// Sheth & Tormen and Jenkins et al. mass functions from sigma(M), and binned counts against them.
#include "groups/MassFunction.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace fountain::groups {

namespace {
constexpr double kDeltaC = 1.686;
constexpr double kStA = 0.707, kStP = 0.3;
}  // namespace

double sheth_tormen_multiplicity(double sigma) {
  // A = 1 / (1 + 2^-p Gamma(1/2 - p) / sqrt(pi)) makes int f dln(1/sigma) = 1.
  static const double norm =
      1.0 / (1.0 + std::pow(2.0, -kStP) * std::tgamma(0.5 - kStP) / std::sqrt(std::numbers::pi));
  const double nu2 = kDeltaC * kDeltaC / (sigma * sigma);
  return norm * std::sqrt(2.0 * kStA / std::numbers::pi) * (1.0 + std::pow(1.0 / (kStA * nu2), kStP)) *
         std::sqrt(nu2) * std::exp(-0.5 * kStA * nu2);
}

double jenkins_multiplicity(double sigma) {
  const double x = std::log(1.0 / sigma);
  if (!(x >= -1.2 && x <= 1.05)) return std::numeric_limits<double>::quiet_NaN();
  return 0.315 * std::exp(-std::pow(std::fabs(x + 0.61), 3.8));
}

MassFunctionModel::MassFunctionModel(cosmology::LinearPowerSpectrum spectrum, double mean_density, double growth)
    : spectrum_(std::move(spectrum)), mean_density_(mean_density), growth_(growth) {
  if (!(mean_density > 0.0) || !std::isfinite(mean_density))
    throw std::invalid_argument("mass function: the mean density must be positive");
  if (!(growth > 0.0) || !std::isfinite(growth)) throw std::invalid_argument("mass function: the growth must be positive");
}

double MassFunctionModel::radius(double mass) const {
  return std::cbrt(3.0 * mass / (4.0 * std::numbers::pi * mean_density_));
}

double MassFunctionModel::sigma(double mass) const { return growth_ * spectrum_.sigma(radius(mass)); }

double MassFunctionModel::slope(double mass) const {
  const double h = 0.01;
  auto ln_inv_sigma = [&](double step) { return -std::log(sigma(mass * std::exp(step * h))); };
  return (ln_inv_sigma(-2) - 8.0 * ln_inv_sigma(-1) + 8.0 * ln_inv_sigma(1) - ln_inv_sigma(2)) / (12.0 * h);
}

double MassFunctionModel::dn_dln_mass(double mass, MassFunctionFit fit) const {
  const double s = sigma(mass);
  const double f = fit == MassFunctionFit::sheth_tormen ? sheth_tormen_multiplicity(s) : jenkins_multiplicity(s);
  return mean_density_ / mass * f * slope(mass);
}

double MassFunctionModel::expected_count(double mass_lo, double mass_hi, double volume, MassFunctionFit fit) const {
  constexpr int kIntervals = 16;
  const double a = std::log(mass_lo), b = std::log(mass_hi), step = (b - a) / kIntervals;
  double sum = 0.0;
  for (int i = 0; i <= kIntervals; ++i) {
    const double w = i == 0 || i == kIntervals ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += w * dn_dln_mass(std::exp(a + i * step), fit);
  }
  return volume * sum * step / 3.0;
}

std::vector<MassFunctionBin> bin_mass_function(std::span<const double> masses, double volume, const MassFunctionModel& model,
                                               double log_min, double log_max, double width) {
  if (!(width > 0.0) || !(log_max > log_min))
    throw std::invalid_argument("mass function: the bins need log_max > log_min and a positive width");
  const auto n = static_cast<std::size_t>(std::ceil((log_max - log_min) / width - 1e-9));
  std::vector<MassFunctionBin> bins(n);
  for (std::size_t k = 0; k < n; ++k) {
    MassFunctionBin& b = bins[k];
    b.log_lo = log_min + static_cast<double>(k) * width;
    b.log_hi = b.log_lo + width;
    const double lo = std::pow(10.0, b.log_lo), hi = std::pow(10.0, b.log_hi);
    b.sheth_tormen = model.expected_count(lo, hi, volume, MassFunctionFit::sheth_tormen);
    b.jenkins = model.expected_count(lo, hi, volume, MassFunctionFit::jenkins);
  }
  for (double m : masses) {
    if (!(m > 0.0)) continue;
    const double x = (std::log10(m) - log_min) / width;
    if (x < 0.0) continue;
    const auto k = static_cast<std::size_t>(x);
    if (k < n) ++bins[k].count;
  }
  return bins;
}

}  // namespace fountain::groups
