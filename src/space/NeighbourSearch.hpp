// Gas neighbour searches beyond the SPH loops: everything within a radius, and the k nearest of a kind.
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

#include "core/Vec3.hpp"
#include "particles/GasParticles.hpp"
#include "space/Space.hpp"

namespace fountain {

// Distance from a point to a leaf's box (nearest periodic image), less how far its
// particles may have moved out of it since the rebuild.
double reach_distance(const Space& space, const Vec3& p, const Cell& leaf);

// Calls fn(j, dx, r) for every gas particle j with |x_j - p| < radius (dx = x_j - p as
// nearest image), leaf by leaf in the space's fixed order.
void for_each_within(const Space& space, const GasParticles& gas, const Vec3& p, double radius,
                     const std::function<void(std::size_t, const Vec3&, double)>& fn);

// The k nearest gas particles to p (not `self`) that pass `accept`, nearest first (ties by
// storage index, so the answer is reproducible), searched outward up to max_radius (<= 0: no limit).
// Fewer than k when fewer exist within reach.
std::vector<std::size_t> nearest(const Space& space, const GasParticles& gas, const Vec3& p, std::size_t self,
                                 std::size_t k, double max_radius, const std::function<bool(std::size_t)>& accept);

}  // namespace fountain
