// Structure-of-arrays storage of the gas (SPH) particles, one vector per field.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/ForEach.hpp"
#include "core/Vec3.hpp"
#include "particles/TimeBin.hpp"

namespace fountain {

// Every field is a separate vector so a loop touches only what it needs. Positions and
// velocities are physical in a non-cosmological run; in a comoving run they will be the
// comoving position and the peculiar-velocity variable of the integrator. Each field has a row
// in the table of particle fields (kGasFields, particles/ParticleFields.hpp), which names it
// and says where it is written and sent.
struct GasParticles {
  // Identity and conserved state.
  std::vector<std::uint64_t> id;
  std::vector<double> mass;           // gas mass (what hydro sees)

  // Hybrid gas/star state (paper section 2.2-2.3). Gravity and inertia see mass plus the
  // hidden stellar mass; hydro sees the gas mass alone.
  std::vector<double> mass_initial;       // gas mass at the start (spawning and dissolving thresholds)
  std::vector<double> mass_stars_hidden;  // stars formed and not yet spawned
  std::vector<double> reservoir;          // cold-phase feedback energy held back (energy, not specific)
  std::vector<std::uint8_t> promoted;     // 1 once promoted to the hot phase by feedback
  std::vector<double> promotion_time;     // when it was (last) promoted; -1 if never
  // Set by star formation for this step's feedback task: energy for the hot neighbours.
  std::vector<double> feedback_hot_energy;
  std::vector<Vec3> x;                // position
  std::vector<Vec3> v_full;           // integrated velocity (half-step after a first kick)
  std::vector<double> u_full;         // integrated specific internal energy

  // Predicted state: drifted to the current time, what neighbours read.
  std::vector<Vec3> v;                // predicted velocity
  std::vector<double> u;              // predicted specific internal energy
  std::vector<double> h;              // smoothing length (compact support radius)
  std::vector<double> rho;            // density

  // What the MSPH rule reads: density and h as predicted at the start of the step, frozen
  // while the density loop recomputes rho and h, so every loop decouples the same pairs.
  std::vector<double> rho_msph;
  std::vector<double> h_msph;

  // Density-loop accumulators and results.
  std::vector<double> wcount;         // (4 pi/3) h^3 sum W: the weighted neighbour number
  std::vector<double> wcount_dh;      // d wcount / dh
  std::vector<double> div_v;
  std::vector<Vec3> curl_v;
  // The symmetric part of the velocity gradient (with hydro.viscosity_reconstruction; else 0).
  std::vector<Vec3> strain_diagonal;  // S_xx, S_yy, S_zz
  std::vector<Vec3> strain_shear;     // S_xy, S_xz, S_yz

  // Prepared for the force loop from the predicted state (after each drift and ghost).
  std::vector<double> soundspeed;     // sqrt(gamma (gamma-1) u): depends on u only
  std::vector<double> p_over_rho_a;   // P / rho^alpha of the momentum equation
  std::vector<double> inv_rho_2ma;    // 1 / rho^(2-alpha)
  std::vector<double> balsara;        // Balsara switch f_i
  std::vector<double> entropy;        // P / rho^gamma (with hydro.viscosity_reconstruction; else 0)

  // Force-loop results.
  std::vector<Vec3> a_hydro;
  std::vector<double> du_dt;
  std::vector<double> du_dt_cool;     // the part of du_dt that is radiative cooling (<= 0)
  std::vector<double> v_sig;          // largest signal velocity over the force loop's pairs (>= 2c)

  // Gravity (zero when gravity is off): acceleration and specific potential at the last
  // force computation.
  std::vector<Vec3> a_grav;
  std::vector<double> potential;
  // Periodic TreePM: the mesh's parts of both (included in them), computed at the start of
  // each mesh step and kept through it (zero without the mesh).
  std::vector<Vec3> a_mesh;
  std::vector<double> potential_mesh;

  // Time integration.
  std::vector<TimeBin> time_bin;      // step length = 2^time_bin integer time units
  std::vector<std::int64_t> ti_begin; // integer time the current step began
  std::vector<TimeBin> courant_bin;   // bin the Courant criterion alone allows (set by the ghost)
  std::vector<TimeBin> limit_bin;     // neighbours' smallest bin + 2 (timestep limiter)
  std::vector<TimeBin> wake_bin;      // requested by active neighbours: shorten the step to this bin

  std::size_t size() const { return id.size(); }

  // Every field takes `n` entries; new particles take the table's initial values.
  void resize(std::size_t n);

  // Calls f(field) for every per-particle vector, in the table's order (reordering, packing
  // for other ranks).
  template <class F>
  void for_each_field(F&& f);

  // The derived fields (flagged in the table): worked out again from a particle's own state
  // before anything reads them in a step (a leaf's drift task prepares the force inputs and
  // the MSPH rule's frozen h and density of every particle the step reads; a ghost sets the
  // Courant bin of each particle it finishes). A recut need not move them, nor a holder
  // receive them.
  template <class F>
  void for_each_derived_field(F&& f);

  // Mass that gravity and inertia see: gas plus hidden stars.
  double dynamical_mass(std::size_t i) const { return mass[i] + mass_stars_hidden[i]; }

  // Reorder every field by `order` (new index k holds old particle order[k]); an order
  // shorter than the particle number keeps only the particles it names. Pieces of each field
  // are moved through `for_each` when given. A caller that permutes often passes `scratch`
  // to keep between calls (a fresh buffer is zero-filled and faulted in each time).
  // A recut may leave the derived fields in place (`Derived::Stay`): a particle's slot then
  // holds another's stale values until its step works them out. An order that changes the
  // number of particles moves them as every field.
  enum class Derived { Move, Stay };
  void permute(const std::vector<std::size_t>& order, const ForEach& for_each = {},
               std::vector<std::byte>* scratch = nullptr, Derived derived = Derived::Move);
};

}  // namespace fountain

// The table of fields, and the members above that walk it: at the end, so that every user of
// the store has them.
#include "particles/ParticleFields.hpp"
