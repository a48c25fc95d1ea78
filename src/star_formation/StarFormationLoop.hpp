// Star formation as cell tasks: gas converted into hidden stellar mass, and the spawning of star particles and dissolving of spent gas between steps.
#pragma once
#include <cstdint>

#include "core/IdealGas.hpp"
#include "feedback/FeedbackLoop.hpp"
#include "star_formation/StarFormationLaw.hpp"
#include "star_formation/StarFormationParams.hpp"
#include "step/StarFormationTally.hpp"
#include "step/StepContext.hpp"

namespace fountain::star_formation {

// Everything the star formation tasks share, owned by the engine.
struct StarFormationState {
  StarFormationParams params;
  StarFormationLaw law;
  TemperatureOf temperature;        // T (K) of specific energy u
  StarFormationTally step_tally;    // spawning's and dissolving's share
  double time = 0.0;                // stars' birth times: t, or a in comoving runs
};

// Task: the active gas of leaf c converts mass over its coming step; the feedback of what
// formed is deposited (its own share heats the gas now) and the cell's feedback sites listed.
void form_stars(StepContext& ctx, const StarFormationState& sf, feedback::FeedbackState& fb, int c);

// Between steps: spawns star particles from hidden mass and dissolves gas that fell below
// the threshold into its neighbours (its mass marked 0, removed at the next rebuild).
// Returns whether any particle was created or dissolved.
bool spawn_and_dissolve(StepContext& ctx, StarFormationState& sf, std::uint64_t& next_id);

}  // namespace fountain::star_formation
