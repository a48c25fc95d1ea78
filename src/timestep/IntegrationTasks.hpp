// The time integration's tasks: drift, the two half-kicks and the new timesteps of a leaf.
#pragma once
#include "step/StepContext.hpp"
#include "step/StepTasks.hpp"

namespace fountain::integration {

struct IntegrationTaskTypes {
  int drift = -1, kick_close = -1, timestep = -1, kick_open = -1;
};

IntegrationTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx);

}  // namespace fountain::integration
