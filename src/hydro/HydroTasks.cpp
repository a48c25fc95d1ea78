#include "hydro/HydroTasks.hpp"

#include "hydro/HydroLoops.hpp"

namespace fountain::hydro {

HydroTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, int drift, int kick_close) {
  HydroTaskTypes t;
  StepContext* c = &ctx;
  auto gas_leaf = [](TaskKind k) {
    k.gas_leaves_only = true;
    return k;
  };
  t.density = tasks.add(gas_leaf(TaskKind::leaf({"density", "", "hydro"}, Stage::Density,
                                                [c](const tasks::Task& task) { density(*c, task.ci); })));
  t.ghost = tasks.add(gas_leaf(TaskKind::leaf({"ghost", "", "hydro"}, Stage::Ghost,
                                              [c](const tasks::Task& task) { ghost(*c, task.ci); })));
  t.force = tasks.add(gas_leaf(TaskKind::leaf({"force", "", "hydro"}, Stage::Force,
                                              [c](const tasks::Task& task) { force(*c, task.ci); })));
  // A leaf's loops read its neighbour leaves: the density after their drift, the force after
  // their ghost, and both before those close their step (the kick rewrites the predicted state).
  tasks.link([t, drift, kick_close](GraphBuilder& g) {
    for (int c : g.leaves()) {
      const int d = g.task(t.density, c);
      if (d >= 0)
        for (int n : g.neighbours(c)) g.depends(g.task(drift, n), d);
    }
    for (int c : g.leaves()) {
      const int f = g.task(t.force, c);
      if (f < 0) continue;
      for (int n : g.neighbours(c)) {
        g.depends(g.task(t.ghost, n), f);
        g.depends(f, g.task(kick_close, n));
      }
    }
  });
  return t;
}

}  // namespace fountain::hydro
