// What a gravity calculation is asked (a target) and what it answers (acceleration, potential, cost).
#pragma once
#include <cstdint>

#include "core/Vec3.hpp"

namespace fountain::gravity {

// The first force computation of a run has no previous acceleration to scale the relative
// opening criterion by; the walk then uses the Barnes-Hut angle instead (as GADGET-2 does).
inline constexpr double kNoOldAcceleration = -1.0;

struct GravityTarget {
  Vec3 position;
  double softening = 0.0;               // Plummer-equivalent eps of the target
  double a_old = kNoOldAcceleration;    // |a| of the previous force computation, G included
  std::int64_t source_index = -1;       // the target's own index among the sources, or -1
};

struct GravityResult {
  Vec3 acceleration;
  double potential = 0.0;  // excludes the target's self-potential (GADGET-2 removes it too)
  std::int64_t node_interactions = 0;
  std::int64_t particle_interactions = 0;

  std::int64_t interactions() const { return node_interactions + particle_interactions; }
};

}  // namespace fountain::gravity
