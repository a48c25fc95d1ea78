// Radiative cooling's task: a leaf's gas cooled over its coming step.
#pragma once
#include "step/StepContext.hpp"
#include "step/StepTasks.hpp"

namespace fountain::cooling {

int register_tasks(StepTasks& tasks, StepContext& ctx);

}  // namespace fountain::cooling
