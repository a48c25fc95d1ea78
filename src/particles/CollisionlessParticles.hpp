// Structure-of-arrays storage of the collisionless particles: dark matter and stars.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/ForEach.hpp"
#include "core/Vec3.hpp"
#include "particles/TimeBin.hpp"

namespace fountain {

// GADGET's particle types: what a snapshot calls PartType1, PartType2 and PartType4. Type 2
// is a zoom's low-resolution dark matter, of several masses (files' types 2, 3 and 5).
enum class Species : std::uint8_t { DarkMatter = 1, LowResDarkMatter = 2, Star = 4 };
inline const char* species_name(Species s) {
  return s == Species::Star ? "star" : s == Species::LowResDarkMatter ? "low-resolution dark matter" : "dark matter";
}

// Dark matter and stars move under gravity alone: a position, the integrated velocity and
// the gravitational acceleration, on their own individual timesteps. They share one store
// (and one index range per cell) because every task treats them alike; only softening and
// outputs tell them apart. In a comoving run x will be the comoving position and v_full the
// integrator's velocity variable, as for the gas. Each field has a row in the table of
// particle fields (kCollisionlessFields, particles/ParticleFields.hpp).
struct CollisionlessParticles {
  std::vector<std::uint64_t> id;
  std::vector<Species> species;
  std::vector<double> birth_time;      // stars: when spawned (simulation time); dark matter: 0
  std::vector<std::uint64_t> parent_id;  // stars: id of the gas particle that formed them
  std::vector<double> mass;
  std::vector<Vec3> x;                 // position
  std::vector<Vec3> v_full;            // integrated velocity (half-step after a first kick)
  std::vector<Vec3> v;                 // predicted velocity at the last drift (what outputs show)

  std::vector<Vec3> a_grav;            // gravitational acceleration at the last force computation
  std::vector<double> potential;       // specific gravitational potential there (for diagnostics)
  std::vector<Vec3> a_mesh;            // periodic TreePM: the mesh's parts of both, from the
  std::vector<double> potential_mesh;  // start of the mesh step (zero without the mesh)

  std::vector<TimeBin> time_bin;
  std::vector<std::int64_t> ti_begin;

  std::size_t size() const { return id.size(); }

  // Every field takes `n` entries; new particles take the table's initial values.
  void resize(std::size_t n);

  // Calls f(field) for every per-particle vector, in the table's order (see GasParticles).
  template <class F>
  void for_each_field(F&& f);

  std::size_t count(Species s) const {
    std::size_t n = 0;
    for (Species k : species) n += k == s ? 1 : 0;
    return n;
  }

  // Appends one particle (fields not given are zero), for stars spawned by gas.
  void push_back(std::uint64_t new_id, Species s, double m, const Vec3& pos, const Vec3& vel_full, const Vec3& vel,
                 double born, std::uint64_t parent) {
    const std::size_t n = size();
    resize(n + 1);
    id[n] = new_id; species[n] = s; mass[n] = m; x[n] = pos; v_full[n] = vel_full; v[n] = vel;
    birth_time[n] = born; parent_id[n] = parent;
  }

  // Reorder every field by `order` (new index k holds old particle order[k]); `scratch` as
  // for GasParticles::permute.
  void permute(const std::vector<std::size_t>& order, const ForEach& for_each = {},
               std::vector<std::byte>* scratch = nullptr);
};

}  // namespace fountain

// The table of fields, and the members above that walk it (see GasParticles.hpp).
#include "particles/ParticleFields.hpp"
