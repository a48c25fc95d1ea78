// Structure-of-arrays storage of the collisionless (dark matter) particles.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/Vec3.hpp"
#include "particles/GasParticles.hpp"

namespace fountain {

// Dark matter moves under gravity alone: a position, the integrated velocity and the
// gravitational acceleration, on its own individual timesteps. In a comoving run x will be
// the comoving position and v_full the integrator's velocity variable, as for the gas.
struct DarkMatterParticles {
  std::vector<std::uint64_t> id;
  std::vector<double> mass;
  std::vector<Vec3> x;                 // position
  std::vector<Vec3> v_full;            // integrated velocity (half-step after a first kick)
  std::vector<Vec3> v;                 // predicted velocity at the last drift (what outputs show)

  std::vector<Vec3> a_grav;            // gravitational acceleration at the last force computation
  std::vector<double> potential;       // specific gravitational potential there (for diagnostics)

  std::vector<TimeBin> time_bin;
  std::vector<std::int64_t> ti_begin;

  std::size_t size() const { return id.size(); }

  void resize(std::size_t n) {
    id.resize(n); mass.resize(n); x.resize(n); v_full.resize(n); v.resize(n);
    a_grav.resize(n); potential.resize(n);
    time_bin.resize(n); ti_begin.resize(n);
  }

  // Reorder every field by `order` (new index k holds old particle order[k]).
  void permute(const std::vector<std::size_t>& order);
};

}  // namespace fountain
