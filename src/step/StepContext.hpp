// What every task of a step needs: the particles, the cells, the parameters and the clock.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>

#include <memory>
#include <vector>

#include "core/ForEach.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "space/Space.hpp"
#include "step/TimeLine.hpp"

namespace fountain {

// The physics modules' settings and state, below which this layer sits: named, not included.
struct HydroParams;
struct GravityParams;
class Collectives;
namespace cooling {
class RadiativeCooling;
}
namespace gravity {
class GravityTree;
class TreeAcrossRanks;
struct LongRangeForce;
}

struct IntegrationParams {
  double dt_min = 1e-8;
  double dt_max = 1e-6;
  double max_dln_a = 0.01;  // comoving runs: the largest step in ln a
};

struct StepContext {
  GasParticles& gas;
  Space& space;
  const HydroParams& hydro;
  const IntegrationParams& integration;
  const TimeLine& timeline;
  CollisionlessParticles& dm;
  const GravityParams& gravity;

  // Radiative cooling, when on (the engine owns it). Without it the kicks never let u fall
  // below half in one kick; with it the cooling task's implicit rate keeps u positive.
  const cooling::RadiativeCooling* cooling = nullptr;

  // This step's gravity tree: built after each recut of the cells, refitted by the tree
  // tasks in the steps between.
  std::unique_ptr<gravity::GravityTree> tree;
  // Set when the tree was built at the particles' present positions (at a rebuild, before the
  // step's graph): the step's tree tasks then have nothing to do.
  bool tree_current = false;
  // Set for the engine's first force pass only, which has no previous accelerations: the walk
  // then opens nodes by the Barnes-Hut angle. Every later pass scales the relative criterion by
  // each particle's |a_old|, even an exact 0 (a lattice point whose pair forces cancel, which
  // then opens every node), rather than falling back to the cruder angle for its group.
  bool first_forces = false;
  // Across ranks (each rank walking its own leaves): the tree's part this rank builds and
  // refits, and the messages that assemble each step's tree from it (docs/gravity.md, "Across
  // ranks"); null when the tree is built whole from every particle.
  std::unique_ptr<gravity::TreeAcrossRanks> tree_across{};
  Collectives* tree_messages = nullptr;
  // The order in which this rank gives its own particles to tree_across, found at its build:
  // each source's name (gas index, or the gas arrays' size + collisionless index) and place
  // in the run; the first `gas` are gas. The arrays' sizes then are kept to check it.
  struct OwnSourceOrder {
    std::vector<std::int32_t> names;
    std::vector<std::uint64_t> places;
    std::size_t gas = 0, gas_arrays = 0, dm_arrays = 0;
  };
  OwnSourceOrder own_source_order{};
  // Whether this rank owns leaf c (its tasks run here); every leaf when alone.
  std::function<bool(int)> owns_leaf = [](int) { return true; };
  // Where each cell's gas starts in the run's order, where this rank's arrays hold only some
  // leaves (halo mode); null when they hold every particle in the run's order.
  const std::vector<std::size_t>* leaf_places = nullptr;
  // The same for the collisionless particles (halo mode), whose places follow every gas
  // particle's (*gas_total of them in the run).
  const std::vector<std::size_t>* leaf_dm_places = nullptr;
  const std::size_t* gas_total = nullptr;
  // Halo mode: a leaf's collisionless particles are in the arrays of its owner only (a holder
  // drifts the leaf's gas, not them).
  bool halo_mode = false;
  // What this graph run's tree tasks do (gravity::plan_tree_update, before the run).
  enum class TreeUpdate { keep, refit, build };
  TreeUpdate tree_update = TreeUpdate::build;

  // Periodic boxes: the long-range mesh and its forces (TreePM); null for open boundaries.
  std::unique_ptr<gravity::LongRangeForce> long_range{};

  IntegerTime ti_current = 0;

  // Comoving runs (docs/physics.md §11): the timeline in ln a, and the expansion at
  // ti_current, which the force and timestep calculations read; null for plain time.
  const ComovingTimeLine* comoving = nullptr;
  struct Expansion {
    double a = 1.0;
    double hubble = 0.0;       // H(a), internal units
    double hubble_flow = 0.0;  // a^2 H: the Hubble flow's part of v' per comoving length

    // Sub-grid physics reads physical values (docs/physics.md §11, "Sub-grid physics"):
    // rho = rho' / a^3, u = u' / a^2 (gamma = 5/3), h = a h', c = c' / a,
    // div v = D' / a^2 + 3 H; a heating du changes u' by a^2 du. All identities in plain runs.
    double density(double rho_comoving) const { return rho_comoving / (a * a * a); }
    double energy(double u_comoving) const { return u_comoving / (a * a); }
    double code_energy(double u_physical) const { return u_physical * a * a; }
    double length(double h_comoving) const { return a * h_comoving; }
    double speed(double c_comoving) const { return c_comoving / a; }
    double divergence(double d_comoving) const { return d_comoving / (a * a) + 3.0 * hubble; }
  };
  Expansion expansion{};
  // The factor on every comoving softening at ti_current (GravityParams::softening_factor;
  // 1 in plain runs).
  double softening_factor = 1.0;
  double softening_gas() const;
  double softening_of(std::size_t dm_index) const;  // of collisionless particle dm_index
  // Comoving runs: the RMS-displacement limits of the physical step, per species (set at each
  // recut; infinite otherwise).
  double dt_rms_gas = std::numeric_limits<double>::infinity();
  double dt_rms_dark_matter = std::numeric_limits<double>::infinity();
  // Comoving TreePM (docs/physics.md §11, "The mesh step"): the mesh force is computed at the
  // start of its own step, when every particle is synchronised, and kicks over that step's
  // halves; no particle's bin exceeds the mesh step's. Inactive (bin < 0) in other runs,
  // where a periodic mesh is recomputed with every force.
  struct MeshStep {
    int bin = -1;              // the current mesh step's bin (-1: none)
    IntegerTime ti_begin = 0;  // and its start
    // For the step at ti_current: whether the mesh is computed now, and the gravity kick
    // factors of its force: from the last mesh step's midpoint to now (closing), from now to
    // the new one's midpoint (opening), and from the current mesh step's midpoint to now
    // (what a particle's predicted velocity adds to its integrated one between mesh steps).
    bool due = false;
    double close_kick = 0.0, open_kick = 0.0, predict_kick = 0.0;
    bool active() const { return bin >= 0; }
    IntegerTime ti_end() const { return ti_begin + (IntegerTime{1} << bin); }
    double midpoint() const { return static_cast<double>(ti_begin) + 0.5 * static_cast<double>(IntegerTime{1} << bin); }
  };
  MeshStep mesh_step{};
  // Whether this step's gravity computes the mesh (every force without a mesh step).
  bool mesh_due() const { return !mesh_step.active() || mesh_step.due; }
  // A step of `bin` from ti_current: its cosmic time, which sub-grid rates integrate over,
  // and the energy equation's factor (int dt / a^2 comoving; both the step in plain runs).
  struct StepSpan {
    double time, energy;
  };
  StepSpan step_span(int bin) const;
  // Sets ti_current and the expansion there.
  void set_time(IntegerTime ti);
  // x += v_full * drift_factor over [t0, t1]: the interval itself, or comoving, int dt / a^2.
  double drift_factor(IntegerTime t0, IntegerTime t1) const {
    return comoving ? comoving->drift(static_cast<double>(t0), static_cast<double>(t1)) : timeline.drift_factor(t0, t1);
  }

  // A parallel loop for use inside a task (Executor::for_each_in_task), empty on one thread:
  // a task whose work splits (a cell's gravity walk) lets idle threads help, so that a big
  // task at the end of a step does not leave them waiting.
  ForEach in_task_for_each = {};

  // Set by tasks, read by the engine after the step.
  std::atomic<bool> cover_exceeded{false};  // some h outgrew its cell's cover: rebuild
  std::atomic<int> h_capped{0};             // particles whose h was capped by the cover
  std::atomic<int> h_max_capped{0};         // particles held at hydro.h_max with too few neighbours
  std::atomic<int> h_min_held{0};           // particles held at the floor of h with more neighbours
  // Force interactions (i's of j) the MSPH rule dropped: what tells an MSPH run from an SPH one.
  std::atomic<long long> msph_decoupled{0};

  bool is_active(std::size_t i) const { return TimeLine::active(gas.time_bin[i], ti_current); }
  bool is_active_dm(std::size_t i) const { return TimeLine::active(dm.time_bin[i], ti_current); }

  // The bin a particle's step would take on the Courant criterion alone, capped by dt_max
  // and alignment: what the limiter compares with the neighbours' bins.
  int courant_bin(std::size_t i) const;
};

}  // namespace fountain
