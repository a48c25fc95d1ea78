// Feedback's tasks: each leaf's search for its sites' hot neighbours, then one task that hands the energy out in a fixed order.
#pragma once
#include "feedback/FeedbackLoop.hpp"
#include "step/StepTasks.hpp"

namespace fountain::feedback {

struct FeedbackTaskTypes {
  int search = -1, apply = -1;
};

// star_formation_done: star formation's per-step task, after which every leaf has formed
// its stars and listed its sites.
FeedbackTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, FeedbackState& fb, int star_formation_done);

}  // namespace fountain::feedback
