// Drift, kick and timestep of the particles of one cell (leapfrog KDK, individual steps).
#pragma once
#include "step/StepContext.hpp"

namespace fountain::integration {

// Who prepares a drifted particle's force inputs (sound speed, pressure terms, Balsara switch).
enum class ForceInputs {
  // The drift, for every particle: the state is then whole (snapshots, restart files).
  Drift,
  // The drift of a step's graph: its ghosts prepare them anew for every active particle and,
  // without the MSPH rule, nothing reads them before, so the drift prepares them only for the
  // inactive particles (the force loop reads those as predicted).
  UnlessGhost,
  // Nobody yet: the drift before a recut. Whatever reads them in a step reads a leaf that a
  // drift task of that step drifts first (a neighbour of an active leaf is drifted), and that
  // task prepares them, from the same state: preparing them here too was wasted work.
  Later,
};

// Predicts every particle of the cell to the current time: positions, velocities,
// internal energy, h and density; freezes what the MSPH rule will read this step.
void drift(StepContext& ctx, int c, ForceInputs force_inputs = ForceInputs::Drift);

// Closes the step of each active particle with its second half-kick.
void kick_close(StepContext& ctx, int c);

// New time bins for the active particles (Courant criterion, dt_max, alignment).
void timestep(StepContext& ctx, int c);

// Opens the new step of each active particle with its first half-kick.
void kick_open(StepContext& ctx, int c);

// Shortens the steps of particles that short-step neighbours asked to wake (the timestep
// limiter): each ends at the next boundary of its requested bin. Runs between steps.
void wake(StepContext& ctx, int c);

// One tick of the timeline and the span it divides, for messages about steps or times too
// short to be told apart.
std::string tick_text(const TimeLine& t);

}  // namespace fountain::integration
