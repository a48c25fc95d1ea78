// Star formation as cell tasks: gas converted into hidden stellar mass, and the spawning of star particles and dissolving of spent gas between steps.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>

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

// Whether gas particle i's hidden stars are due to become a star particle.
bool due_to_spawn(const GasParticles& gas, const StarFormationParams& p, std::size_t i);
// Whether gas particle i has so little gas left that it is due to dissolve.
bool due_to_dissolve(const GasParticles& gas, const StarFormationParams& p, std::size_t i);

// Gas particle i's hidden stars become a star particle with ID `id`, appended to ctx.dm.
void spawn(StepContext& ctx, StarFormationState& sf, std::size_t i, std::uint64_t id);

// Gas particle i dissolves into its gas neighbours within h (its mass marked 0, removed at the
// next rebuild); `receiver` is called with each neighbour that may take a share. False, and
// nothing moved, if it has no neighbour to take it.
bool dissolve(StepContext& ctx, StarFormationState& sf, std::size_t i,
              const std::function<void(std::size_t)>& receiver = {});

// Between steps: spawns star particles from hidden mass and dissolves gas that fell below
// the threshold into its neighbours, particle by particle in the arrays' order (a dissolve
// may bring a later neighbour's hidden mass to the spawning threshold, or its gas above the
// dissolving one). Returns whether any particle was created or dissolved.
bool spawn_and_dissolve(StepContext& ctx, StarFormationState& sf, std::uint64_t& next_id);

}  // namespace fountain::star_formation
