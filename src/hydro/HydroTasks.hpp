// The SPH loops' tasks: a leaf's density, ghost and force, each gathering over the leaf's neighbours.
#pragma once
#include "step/StepContext.hpp"
#include "step/StepTasks.hpp"

namespace fountain::hydro {

struct HydroTaskTypes {
  int density = -1, ghost = -1, force = -1;
};

// drift and kick_close: the integration's types, which the loops' reads of neighbours wait
// for (drift) and hold back (kick_close rewrites what they read).
HydroTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, int drift, int kick_close);

}  // namespace fountain::hydro
