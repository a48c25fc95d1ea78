// O(N^2) reference gravity with the tree's kernel: the yardstick for tree errors in tests and validation.
#pragma once
#include <span>
#include <vector>

#include "core/Vec3.hpp"
#include "gravity/GravityKernel.hpp"
#include "gravity/GravityTypes.hpp"

namespace fountain::gravity {

struct DirectSums {
  std::vector<Vec3> acceleration;
  std::vector<double> potential;  // without self-potential, like the tree's
};

// Every source on every other. Each pair is evaluated once and applied to both particles with
// opposite signs, so total momentum is conserved to round-off (tests rely on it).
DirectSums direct_summation(std::span<const Vec3> positions, std::span<const double> masses,
                            std::span<const double> softenings, double G,
                            const GravitySplit& split = GravitySplit{});

// All sources on one target (skipping target.source_index); a_old is ignored. For checking a
// few targets of a set too large for direct_summation.
GravityResult direct_on_target(const GravityTarget& target, std::span<const Vec3> positions,
                               std::span<const double> masses, std::span<const double> softenings, double G,
                               const GravitySplit& split = GravitySplit{});

// The periodic short-range force in a box of side `box`: every pair at its nearest image,
// within split.cutoff_radius(), the softened pair force scaled by the split's factors. With
// PeriodicMesh's long range it is the exact TreePM force, which the tree's approximates.
DirectSums direct_summation_periodic(std::span<const Vec3> positions, std::span<const double> masses,
                                     std::span<const double> softenings, double G, double box,
                                     const GravitySplit& split);

}  // namespace fountain::gravity
