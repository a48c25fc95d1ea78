// Gravity's tasks: one tree per step, refitted in parts and finished above them, each leaf's walk of it, and in periodic boxes the long-range mesh.
#pragma once
#include "step/StepContext.hpp"
#include "step/StepTasks.hpp"

namespace fountain::gravity {

struct GravityTaskTypes {
  int refit = -1, tree = -1, walk = -1, mesh = -1;  // mesh: periodic boxes only
};

// drift: the integration's type; the tree is made from every leaf's drifted particles.
GravityTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, int drift);

}  // namespace fountain::gravity
