// What the table of particle fields says about one field: its names, units and description, and where it goes.
#pragma once
#include <cstdint>
#include <type_traits>
#include <vector>

namespace fountain {

// A field's units as powers of the internal units of mass, length and time, and the power of
// the scale factor a that turns what a comoving run stores into the physical value (positions
// a^1, densities a^-3). An ideal gas's specific energies and pressures take powers that depend
// on the adiabatic index, as SWIFT writes them: the whole power of a is
// a + a_gamma gamma + a_gamma_minus_1 (gamma - 1).
struct Dimensions {
  double mass = 0, length = 0, time = 0;
  double a = 0, a_gamma = 0, a_gamma_minus_1 = 0;
  // The force loop's factors P / rho^alpha and 1 / rho^(2 - alpha) and the entropy function
  // P / rho^gamma take powers that depend on hydro.sph_alpha or hydro.gamma (their descriptions
  // give them); such a field cannot be written to snapshots.
  bool depends_on_parameters = false;
};

// The power of a for a run with adiabatic index `gamma` (each term in SWIFT's form, so that
// the snapshot attributes hold the same bits as SWIFT's expressions give).
inline double a_power(const Dimensions& d, double gamma) {
  return d.a + d.a_gamma * gamma + d.a_gamma_minus_1 * (gamma - 1.0);
}

// When a field is written to snapshots.
enum class InSnapshots : std::uint8_t {
  never,
  always,
  with_star_formation,  // gas, in a run with star formation
  stars_only,           // collisionless, in /PartType4 and not /PartType1
};

// The MPI messages a field travels in, as bit flags. src/engine/CellMessages.cpp builds each
// message from the table, its fields in table order. The ghost message is three parts in turn
// and halo mode's changed gas two, each part a flag of its own, which keeps their layouts.
using Messages = std::uint16_t;
namespace message {
// A cell's whole state (pack_cell_state, StateFields::All): the state gathered for outputs.
inline constexpr Messages whole_state = 1u << 0;
// What a step may change of it (StateFields::StepChanged), to ranks that drift every cell.
inline constexpr Messages step_state = 1u << 1;
// The ghost message's first part, the density loop's results the ghost finishes; also the
// first part of halo mode's changed gas, unless the ghost message brought them.
inline constexpr Messages ghost_density = 1u << 2;
// The ghost message's second part: the bin the Courant criterion allows.
inline constexpr Messages ghost_bin = 1u << 3;
// The ghost message's third part: what the ghost prepares for the force loops.
inline constexpr Messages ghost_force_inputs = 1u << 4;
// Halo mode's changed gas (pack_moved_gas), second part: what a step writes after the ghost.
inline constexpr Messages halo_after_ghost = 1u << 5;
// Halo mode's changed gas, third part, in runs with gravity: what the walk writes that a
// holder's own drift of the leaf reads (the acceleration, for the predicted velocities).
inline constexpr Messages halo_gravity = 1u << 6;
// A particle sent whole to another rank (pack_particles): to its top cell's owner at a
// recut, or to a holder of its leaf that had no copy of it.
inline constexpr Messages migration = 1u << 7;
// Halo mode's changed gas, fourth part, in periodic runs: the mesh's acceleration, which a
// holder's own drift reads (the predicted velocity within a mesh step).
inline constexpr Messages halo_mesh = 1u << 8;
// Halo mode's changed gas, fifth part, in runs with star formation: the masses conversion
// moves between gas and hidden stars.
inline constexpr Messages halo_star_formation = 1u << 9;
// What spawning or dissolving a particle between steps changes of it and of the neighbours
// it dissolves into, sent to the other holders of their copies in halo mode.
inline constexpr Messages star_formation_event = 1u << 10;
}  // namespace message

struct FieldInfo {
  const char* key;          // the member's name, which names the field in restart files
  const char* name;         // its dataset in snapshots: SWIFT's name where SWIFT has the quantity
  Dimensions units;
  const char* description;  // one line, a snapshot dataset's Description attribute
  InSnapshots snapshot = InSnapshots::never;
  bool restart = true;
  // Worked out again from the particle's own state before anything reads it in a step: a
  // recut leaves it in place, and halo mode does not send it to the ranks holding a copy.
  bool derived = false;
  Messages messages = 0;
};

// One row of a table: the descriptor, the store's vector, and a new particle's value.
template <class Store, class T>
struct Field {
  using Value = T;
  FieldInfo info;
  std::vector<T> Store::*member;
  T initial;
};

template <class Store, class T>
constexpr Field<Store, T> field(std::vector<T> Store::*member, FieldInfo info, std::type_identity_t<T> initial = T{}) {
  return {info, member, initial};
}

}  // namespace fountain
