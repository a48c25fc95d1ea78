#include "analysis/HydroReference.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/Error.hpp"
#include "ics/TestProblems.hpp"

namespace fountain::analysis {

SodExact::SodExact(const std::string& table_path) {
  std::ifstream in(table_path);
  if (!in) throw InputError(fmt::format("{}: cannot open the exact Sod solution", table_path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    double a = 0, b = 0;
    if (ss >> a >> b) {
      x_.push_back(a);
      rho_.push_back(b);
    }
  }
  if (x_.size() < 2) throw InputError(fmt::format("{}: no data rows", table_path));
}

double SodExact::density(double x) const {
  const auto it = std::lower_bound(x_.begin(), x_.end(), x);
  if (it == x_.begin()) return rho_.front();
  if (it == x_.end()) return rho_.back();
  const std::size_t k = static_cast<std::size_t>(it - x_.begin());
  const double w = (x - x_[k - 1]) / (x_[k] - x_[k - 1]);
  return rho_[k - 1] + w * (rho_[k] - rho_[k - 1]);
}

double sod_density_l1(const GasParticles& g, const SodExact& exact, double x0, double half_width) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double dx = g.x[i].x - x0;
    if (std::fabs(dx) >= half_width) continue;
    sum += std::fabs(g.rho[i] - exact.density(dx));
    ++n;
  }
  return n > 0 ? sum / static_cast<double>(n) : 0.0;
}

double sedov_shock_radius(const GasParticles& g, const Vec3& centre, const Vec3& box, double rho0, double r_max,
                          int nbins) {
  std::vector<double> sum(static_cast<std::size_t>(nbins), 0.0);
  std::vector<int> count(static_cast<std::size_t>(nbins), 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    Vec3 d = g.x[i] - centre;
    for (int k = 0; k < 3; ++k) d[k] -= box[k] * std::round(d[k] / box[k]);
    const int b = static_cast<int>(norm(d) / r_max * nbins);
    if (b >= nbins) continue;
    sum[static_cast<std::size_t>(b)] += g.rho[i];
    ++count[static_cast<std::size_t>(b)];
  }
  std::vector<double> mean(static_cast<std::size_t>(nbins), 0.0);
  for (std::size_t b = 0; b < mean.size(); ++b) mean[b] = count[b] > 0 ? sum[b] / count[b] : 0.0;
  std::size_t peak = 0;
  for (std::size_t b = 0; b < mean.size(); ++b)
    if (mean[b] > mean[peak]) peak = b;
  const double half = rho0 + 0.5 * (mean[peak] - rho0);
  std::size_t b = peak;
  while (b + 2 < mean.size() && mean[b + 1] > half) ++b;
  const double w = mean[b] > mean[b + 1] ? (mean[b] - half) / (mean[b] - mean[b + 1]) : 0.0;
  return (static_cast<double>(b) + 0.5 + w) * r_max / nbins;
}

double sedov_exact_radius(double energy, double rho0, double t) {
  return 1.15167 * std::pow(energy * t * t / rho0, 0.2);
}

double gresho_velocity_l1(const GasParticles& g) {
  double sum = 0.0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double dx = g.x[i].x - 0.5, dy = g.x[i].y - 0.5;
    const double r = std::sqrt(dx * dx + dy * dy);
    const double vphi = r > 0.0 ? (-g.v[i].x * dy + g.v[i].y * dx) / r : 0.0;
    sum += std::fabs(vphi - ics::gresho_velocity(r));
  }
  return sum / static_cast<double>(g.size());
}

}  // namespace fountain::analysis
