// What ranks send each other about a cell: its whole state, its ghost's results, its feedback sites; packed as bytes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/ByteMessages.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "particles/ParticleFields.hpp"
#include "space/Space.hpp"
#include "feedback/FeedbackLoop.hpp"

namespace fountain {

// Which fields a cell's state carries. `All`: every one. `StepChanged`: only what a step's
// tasks can change, for ranks that drift every cell themselves (the replicated state):
// positions change only by the drift, which every rank repeats bit for bit, and identity,
// initial gas mass and the collisionless particles' species, birth, parent and mass never
// change once a particle is made (spawning makes them alike on every rank).
enum class StateFields { All, StepChanged };

// Everything about leaf c: the cell's own record and every field of its gas and collisionless
// particles, except the gas's wake requests (which any rank may make of any particle, and
// which the engine combines across ranks separately).
// Only the particles flagged in `gas_moved` / `dm_moved` (indexed by particle) are carried:
// those active in the step, the only ones a cell's own tasks change (the sender and the
// receiver flag the same ones, from the bins at the start of the step).
void pack_cell_state(MessageWriter& w, const Space& space, GasParticles& gas, CollisionlessParticles& dm, int c,
                     std::span<const char> gas_moved, std::span<const char> dm_moved,
                     StateFields fields = StateFields::All);
void unpack_cell_state(MessageReader& r, Space& space, GasParticles& gas, CollisionlessParticles& dm, int c,
                       std::span<const char> gas_moved, std::span<const char> dm_moved,
                       StateFields fields = StateFields::All);

// What a step changes in a leaf's own record (the rest stands from one recut to the next):
// sent by its owner to every rank, so that all take the same decisions (next time, recut).
struct CellUpdate {
  double h_max = 0.0, v_max = 0.0, dx_max = 0.0, radiated = 0.0;
  std::int64_t ti_drift = 0, ti_end_min = 0;
  static CellUpdate of(const Cell& c) { return {c.h_max, c.v_max, c.dx_max, c.radiated, c.ti_drift, c.ti_end_min}; }
  void apply_to(Cell& c) const {
    c.h_max = h_max, c.v_max = v_max, c.dx_max = dx_max, c.radiated = radiated;
    c.ti_drift = ti_drift, c.ti_end_min = ti_end_min;
  }
};

// The gas fields that a step of a run in halo mode changes other than by the drift (which
// every rank holding a copy repeats alike), and, with gravity, halo_gravity_fields; in
// periodic runs halo_mesh_fields; with star formation (no feedback sites)
// halo_star_formation_fields. The rest stay as they are between recuts in such a run, or no
// holder reads them: identity and initial mass do not change, nor the reservoirs and
// promotions without feedback sites, positions change by the drift alone, the potential is
// read only of own particles. Which field
// travels where is a column of the table of particle fields (particles/ParticleFields.hpp;
// a test checks that each gas field is sent, derived or known not to change).
// They are the ghost's results (ghost_fields, which a ghost message carries whole for the
// force loops of its graph) and what later tasks change. Between graphs a holder needs none
// of the derived fields (GasParticles::for_each_derived_field): its own drift of the leaf
// works them out again before anything reads them.
template <class F>
void halo_ghost_fields(GasParticles& g, F&& f) {
  for_each_field_in(g, message::ghost_density, f);
}
template <class F>
void ghost_fields(GasParticles& g, F&& f) {
  for_each_field_in(g, message::ghost_density, f);
  for_each_field_in(g, message::ghost_bin, f);
  for_each_field_in(g, message::ghost_force_inputs, f);
}
template <class F>
void step_fields_after_ghost(GasParticles& g, F&& f) {
  for_each_field_in(g, message::halo_after_ghost, f);
}
template <class F>
void halo_step_fields(GasParticles& g, F&& f) {
  halo_ghost_fields(g, f);
  step_fields_after_ghost(g, f);
}

template <class F>
void halo_gravity_fields(GasParticles& g, F&& f) {
  for_each_field_in(g, message::halo_gravity, f);
}
template <class F>
void halo_mesh_fields(GasParticles& g, F&& f) {
  for_each_field_in(g, message::halo_mesh, f);
}
template <class F>
void halo_star_formation_fields(GasParticles& g, F&& f) {
  for_each_field_in(g, message::halo_star_formation, f);
}

// The halo_step_fields of leaf c's gas particles flagged in `moved`, without the cell's
// record: what its owner's tasks changed, for the ranks that hold a copy. A rank that had
// the leaf's ghost results in this graph (its send/recv) has the ghost_fields already, as
// they stand at the end of the graph (nothing after the ghost writes them, up to the next
// drift): `ghost_results_sent` then leaves them out.
// With `gravity`, the halo_gravity_fields too; with `mesh` (periodic runs), the
// halo_mesh_fields; with `star_formation`, the halo_star_formation_fields.
void pack_moved_gas(MessageWriter& w, const Space& space, GasParticles& gas, int c, std::span<const char> moved,
                    bool ghost_results_sent = false, bool gravity = false, bool mesh = false, bool star_formation = false);
void unpack_moved_gas(MessageReader& r, const Space& space, GasParticles& gas, int c, std::span<const char> moved,
                      bool ghost_results_sent = false, bool gravity = false, bool mesh = false, bool star_formation = false);

// What spawning or dissolving changed of the gas particles at `indices`
// (message::star_formation_event), for the other ranks that hold copies of them.
void pack_event_fields(MessageWriter& w, GasParticles& gas, std::span<const std::size_t> indices);
void unpack_event_fields(MessageReader& r, GasParticles& gas, std::span<const std::size_t> indices);

// Every field of the particles at `indices` (in that order): a particle migrating at a recut.
void pack_particles(MessageWriter& w, GasParticles& gas, std::span<const std::size_t> indices);
void unpack_particles(MessageReader& r, GasParticles& gas, std::span<const std::size_t> indices);
void pack_particles(MessageWriter& w, CollisionlessParticles& dm, std::span<const std::size_t> indices);
void unpack_particles(MessageReader& r, CollisionlessParticles& dm, std::span<const std::size_t> indices);

// The particles [first, first + count), with every field a cell's whole state carries;
// unpacked into the places [first, first + count) of a store at least that long.
void pack_particle_range(MessageWriter& w, GasParticles& gas, std::size_t first, std::size_t count);
void unpack_particle_range(MessageReader& r, GasParticles& gas, std::size_t first, std::size_t count);
void pack_particle_range(MessageWriter& w, CollisionlessParticles& dm, std::size_t first, std::size_t count);
void unpack_particle_range(MessageReader& r, CollisionlessParticles& dm, std::size_t first, std::size_t count);

// What leaf c's ghost computed, which other cells' force loops read.
void pack_ghost_results(MessageWriter& w, const Space& space, GasParticles& gas, int c);
void unpack_ghost_results(MessageReader& r, Space& space, GasParticles& gas, int c);
std::size_t ghost_results_bytes(const Space& space, int c);

// Leaf c's feedback sites and their hot neighbours (particle indices, the same on every rank).
void pack_feedback_sites(MessageWriter& w, const feedback::CellFeedback& cf);
void unpack_feedback_sites(MessageReader& r, feedback::CellFeedback& cf);

}  // namespace fountain
