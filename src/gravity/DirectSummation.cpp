#include "gravity/DirectSummation.hpp"

#include <cmath>
#include <stdexcept>

namespace fountain::gravity {

namespace {

void check_lengths(std::span<const Vec3> positions, std::span<const double> masses,
                   std::span<const double> softenings) {
  if (masses.size() != positions.size() || softenings.size() != positions.size())
    throw std::invalid_argument("direct summation: positions, masses and softenings differ in length");
}

}  // namespace

DirectSums direct_summation(std::span<const Vec3> positions, std::span<const double> masses,
                            std::span<const double> softenings, double G, const GravitySplit& split) {
  check_lengths(positions, masses, softenings);
  const std::size_t n = positions.size();
  DirectSums out;
  out.acceleration.assign(n, Vec3{});
  out.potential.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 acc_i;
    double pot_i = 0.0;
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec3 dx = positions[i] - positions[j];
      const double r2 = dot(dx, dx);
      const double h = pair_spline_length(softenings[i], softenings[j]);
      if (r2 == 0.0 && h == 0.0) continue;  // as in the tree walk
      const PairGravity g = softened_pair(std::sqrt(r2), h, split);
      const Vec3 f = (G * g.force) * dx;
      acc_i -= masses[j] * f;
      out.acceleration[j] += masses[i] * f;
      pot_i += G * masses[j] * g.potential;
      out.potential[j] += G * masses[i] * g.potential;
    }
    out.acceleration[i] += acc_i;
    out.potential[i] += pot_i;
  }
  return out;
}

GravityResult direct_on_target(const GravityTarget& target, std::span<const Vec3> positions,
                               std::span<const double> masses, std::span<const double> softenings, double G,
                               const GravitySplit& split) {
  check_lengths(positions, masses, softenings);
  GravityResult out;
  for (std::size_t j = 0; j < positions.size(); ++j) {
    if (static_cast<std::int64_t>(j) == target.source_index) continue;
    const Vec3 dx = target.position - positions[j];
    const double r2 = dot(dx, dx);
    const double h = pair_spline_length(target.softening, softenings[j]);
    if (r2 == 0.0 && h == 0.0) continue;
    const PairGravity g = softened_pair(std::sqrt(r2), h, split);
    out.acceleration -= (G * masses[j] * g.force) * dx;
    out.potential += G * masses[j] * g.potential;
    ++out.particle_interactions;
  }
  return out;
}

DirectSums direct_summation_periodic(std::span<const Vec3> positions, std::span<const double> masses,
                                     std::span<const double> softenings, double G, double box,
                                     const GravitySplit& split) {
  check_lengths(positions, masses, softenings);
  if (!split.enabled() || !(box > 0.0) || !(split.cutoff_radius() < 0.5 * box))
    throw std::invalid_argument("periodic direct summation: needs a split whose cut-off is below half the box");
  const std::size_t n = positions.size();
  const double cut2 = split.cutoff_radius() * split.cutoff_radius();
  DirectSums out;
  out.acceleration.assign(n, Vec3{});
  out.potential.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      Vec3 dx = positions[i] - positions[j];
      for (int d = 0; d < 3; ++d) dx[d] -= box * std::nearbyint(dx[d] / box);
      const double r2 = dot(dx, dx);
      const double h = pair_spline_length(softenings[i], softenings[j]);
      if (r2 > cut2 || (r2 == 0.0 && h == 0.0)) continue;
      const PairGravity g = softened_pair(std::sqrt(r2), h, split);
      const Vec3 f = (G * g.force) * dx;
      out.acceleration[i] -= masses[j] * f;
      out.acceleration[j] += masses[i] * f;
      out.potential[i] += G * masses[j] * g.potential;
      out.potential[j] += G * masses[i] * g.potential;
    }
  return out;
}

}  // namespace fountain::gravity
