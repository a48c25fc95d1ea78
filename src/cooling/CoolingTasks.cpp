#include "cooling/CoolingTasks.hpp"

#include "cooling/CoolingLoop.hpp"

namespace fountain::cooling {

int register_tasks(StepTasks& tasks, StepContext& ctx) {
  StepContext* c = &ctx;
  TaskKind cool = TaskKind::leaf({"cooling", "", "cooling"}, Stage::Cooling,
                                 [c](const tasks::Task& task) { cool_cell(*c, task.ci); });
  cool.gas_leaves_only = true;
  return tasks.add(std::move(cool));
}

}  // namespace fountain::cooling
