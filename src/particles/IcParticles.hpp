// Lean particle stores for initial conditions: only the fields an initial conditions file holds, where a run's stores carry some forty.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/Vec3.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"

namespace fountain {

// Gas as a generator builds it and a file holds it: 80 bytes a particle where GasParticles
// takes some 390, so that a box of millions of particles is made within twice the bytes it
// writes. v and u are the velocity and specific internal energy in the run's variables.
struct IcGasParticles {
  std::vector<std::uint64_t> id;
  std::vector<double> mass;
  std::vector<Vec3> x, v;
  std::vector<double> u;
  std::vector<double> h;  // smoothing length; 0: for the run to find

  std::size_t size() const { return id.size(); }
  // Every field takes `n` entries (new ones zero).
  void resize(std::size_t n);
  void push_back(std::uint64_t new_id, double m, const Vec3& pos, const Vec3& vel, double energy, double smoothing);
};

// Dark matter (of either resolution) as a generator builds it and a file holds it.
struct IcCollisionlessParticles {
  std::vector<std::uint64_t> id;
  std::vector<Species> species;
  std::vector<double> mass;
  std::vector<Vec3> x, v;

  std::size_t size() const { return id.size(); }
  // Every field takes `n` entries (new ones zero, species DarkMatter).
  void resize(std::size_t n);
  void push_back(std::uint64_t new_id, Species s, double m, const Vec3& pos, const Vec3& vel);
};

// The same particles in a run's stores, for an engine: v_full = v, u_full = u, mass_initial =
// mass, every other field at its initial value. Taken by value: a moved-from store gives up
// its vectors rather than being copied.
GasParticles to_run_particles(IcGasParticles gas);
CollisionlessParticles to_run_particles(IcCollisionlessParticles dm);

}  // namespace fountain
