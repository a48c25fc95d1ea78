// Multiphase feedback as cell tasks: the energy a star-forming particle deposits, the search for its hot neighbours, their heating, and the promotion of reservoirs.
#pragma once
#include <cstddef>
#include <vector>

#include "core/IdealGas.hpp"
#include "feedback/FeedbackLaw.hpp"
#include "feedback/FeedbackParams.hpp"
#include "step/StarFormationTally.hpp"
#include "step/StepContext.hpp"

namespace fountain::feedback {

using star_formation::StarFormationTally;

// A particle with feedback to hand out or a reservoir to test for promotion, and its
// nearest hot neighbours (found by the cell's search task).
struct FeedbackSite {
  std::size_t particle = 0;
  std::size_t first = 0, count = 0;   // its neighbours in CellFeedback::neighbours
  double mean_hot_temperature = -1.0; // K; negative when none was found
};

// A leaf's feedback of one step; it travels between ranks whole (tally included).
struct CellFeedback {
  std::vector<FeedbackSite> sites;
  std::vector<std::size_t> neighbours;
  StarFormationTally tally;           // this step's star formation and feedback in the cell
};

// Everything the feedback tasks share, owned by the engine.
struct FeedbackState {
  FeedbackParams params;
  double t_star = 4e4;                                // T* (K), star formation's threshold
  double energy_per_mass = 0.0;                       // e_sn per unit internal mass formed
  FeedbackColdPhase cold;
  TemperatureOf temperature;                          // T (K) of specific energy u
  std::function<double(double)> energy_at;            // u of temperature T (K)
  std::vector<CellFeedback> cells;                    // indexed by cell
  StarFormationTally step_tally;                      // the apply task's share
  double time = 0.0;                                  // promotion times: t, or a in comoving runs

  // The phases are physical: a comoving run compares rho' / a^3 and u' / a^2.
  bool is_cold(const StepContext& ctx, std::size_t j) const {
    return cold.contains(ctx.expansion.density(ctx.gas.rho[j]), ctx.expansion.energy(ctx.gas.u[j]));
  }
};

// Called by star formation for active particle i of leaf c as it converts dm into stars: the
// particle's own share heats it now, eps_c fills its reservoir and eps_h waits for the apply task.
void deposit(StepContext& ctx, const FeedbackState& fb, std::size_t i, double dm, CellFeedback& cf);
// Lists active particle i as a site of its cell when it has energy to hand out or a reservoir.
void list_site(const FeedbackState& fb, const GasParticles& gas, std::size_t i, CellFeedback& cf);

// Task: the nearest hot neighbours of each of leaf c's feedback sites (reads other cells).
void find_hot_neighbours(StepContext& ctx, FeedbackState& fb, int c);
// Task (one per step, serial, sites in cell order): eps_h to the hot neighbours, promotion
// of reservoirs that can reach T_prom.
void apply_feedback(StepContext& ctx, FeedbackState& fb, const std::vector<int>& leaves);

// Promotes particle i now: reservoir into u, density without its cold neighbours, hidden
// stars handed to them (mass, momentum and energy conserved).
void promote(StepContext& ctx, FeedbackState& fb, std::size_t i);

}  // namespace fountain::feedback
