#include "timestep/IntegrationTasks.hpp"

#include "timestep/Integration.hpp"

namespace fountain::integration {

IntegrationTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx) {
  IntegrationTaskTypes t;
  StepContext* c = &ctx;
  TaskKind drift = TaskKind::leaf({"drift", "", "integration"}, Stage::Drift, [c](const tasks::Task& task) {
    integration::drift(*c, task.ci, ForceInputs::UnlessGhost);
  });
  drift.activation = TaskKind::Activation::DriftedLeaf;  // every leaf the step reads
  t.drift = tasks.add(std::move(drift));
  t.kick_close = tasks.add(TaskKind::leaf({"kick", "close", "integration"}, Stage::KickClose,
                                          [c](const tasks::Task& task) { kick_close(*c, task.ci); }));
  t.timestep = tasks.add(TaskKind::leaf({"timestep", "", "integration"}, Stage::Timestep,
                                        [c](const tasks::Task& task) { timestep(*c, task.ci); }));
  t.kick_open = tasks.add(TaskKind::leaf({"kick", "open", "integration"}, Stage::KickOpen,
                                         [c](const tasks::Task& task) { kick_open(*c, task.ci); }));
  return t;
}

}  // namespace fountain::integration
