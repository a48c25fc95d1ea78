// Star formation's tasks: each leaf's conversion of gas, and the point after which every leaf has converted.
#pragma once
#include "star_formation/StarFormationLoop.hpp"
#include "step/StepTasks.hpp"

namespace fountain::star_formation {

struct StarFormationTaskTypes {
  int form = -1, done = -1;
};

// The done task does nothing on one rank; across ranks the engine's layout brings every
// rank's converted cells in there, for feedback to read.
StarFormationTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, const StarFormationState& sf,
                                      feedback::FeedbackState& fb);

}  // namespace fountain::star_formation
