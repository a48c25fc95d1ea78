// Drift, kick and timestep of the particles of one cell (leapfrog KDK, individual steps).
#pragma once
#include "engine/StepContext.hpp"

namespace fountain::integration {

// Predicts every particle of the cell to the current time: positions, velocities,
// internal energy, h and density; freezes what the MSPH rule will read this step.
// `before_ghosts`: the drift of a step's graph, whose ghosts then prepare the force inputs of
// every active particle anew; without the MSPH rule nothing reads them before, so the drift
// prepares them only for the inactive particles (the force loop reads those as predicted).
void drift(StepContext& ctx, int c, bool before_ghosts = false);

// Closes the step of each active particle with its second half-kick.
void kick_close(StepContext& ctx, int c);

// New time bins for the active particles (Courant criterion, dt_max, alignment).
void timestep(StepContext& ctx, int c);

// Opens the new step of each active particle with its first half-kick.
void kick_open(StepContext& ctx, int c);

// Shortens the steps of particles that short-step neighbours asked to wake (the timestep
// limiter): each ends at the next boundary of its requested bin. Runs between steps.
void wake(StepContext& ctx, int c);

}  // namespace fountain::integration
