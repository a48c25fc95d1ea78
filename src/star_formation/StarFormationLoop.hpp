// Star formation and MFB feedback as cell tasks, and the spawning and dissolving of particles.
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

#include "step/StepContext.hpp"
#include "star_formation/StarFormationLaw.hpp"
#include "star_formation/StarFormationParams.hpp"
#include "star_formation/StarFormationTally.hpp"

namespace fountain::star_formation {

// A particle with feedback to hand out or a reservoir to test for promotion, and its
// nearest hot neighbours (found by the cell's search task).
struct FeedbackSite {
  std::size_t particle = 0;
  std::size_t first = 0, count = 0;   // its neighbours in CellFeedback::neighbours
  double mean_hot_temperature = -1.0; // K; negative when none was found
};

struct CellFeedback {
  std::vector<FeedbackSite> sites;
  std::vector<std::size_t> neighbours;
  StarFormationTally tally;           // this step's star formation in the cell
};

// Everything the star formation tasks share, owned by the engine.
struct StarFormationState {
  StarFormationParams params;
  StarFormationLaw law;
  double energy_per_mass = 0.0;                      // e_sn per unit internal mass formed
  std::function<double(double)> temperature;         // T (K) of specific energy u
  std::function<double(double)> energy_at;           // u of temperature T (K)
  double u_cold_max = 0.0;                           // energy_at(2 T*): feedback's cold phase is below
  std::vector<CellFeedback> cells;                   // indexed by cell
  StarFormationTally step_tally;                     // the feedback task's and spawning's share
  double time = 0.0;                                 // current simulation time (for promotion times)
};

// Task: the active gas of leaf c converts mass over its coming step, takes its own share of
// the feedback energy and fills its reservoir; lists the cell's feedback sites.
void form_stars(StepContext& ctx, StarFormationState& sf, int c);
// Task: the nearest hot neighbours of each of leaf c's feedback sites (reads other cells).
void find_hot_neighbours(StepContext& ctx, StarFormationState& sf, int c);
// Task (one per step, serial, sites in cell order): eps_h to the hot neighbours, promotion
// of reservoirs that can reach T_prom.
void apply_feedback(StepContext& ctx, StarFormationState& sf, const std::vector<int>& leaves);

// Gas particle j takes gas mass dm_gas and hidden stellar mass dm_hidden moving at v_src
// with specific energy u_src, plus `heat` (energy). Mass and momentum are conserved exactly,
// and the predicted energy too (the kinetic energy the inelastic merger loses becomes heat).
void absorb(GasParticles& gas, std::size_t j, double dm_gas, double dm_hidden, const Vec3& v_src, double u_src,
            double heat, StarFormationTally& tally);

// Promotes particle i now: reservoir into u, density without its cold neighbours, hidden
// stars handed to them (mass, momentum and energy conserved).
void promote(StepContext& ctx, StarFormationState& sf, std::size_t i);

// Between steps: spawns star particles from hidden mass and dissolves gas that fell below
// the threshold into its neighbours (its mass marked 0, removed at the next rebuild).
// Returns whether any particle was created or dissolved.
bool spawn_and_dissolve(StepContext& ctx, StarFormationState& sf, std::uint64_t& next_id);

}  // namespace fountain::star_formation
