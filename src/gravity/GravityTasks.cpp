#include "gravity/GravityTasks.hpp"

#include "gravity/GravityLoop.hpp"
#include "gravity/GravityTree.hpp"

namespace fountain::gravity {

GravityTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, int drift) {
  GravityTaskTypes t;
  StepContext* c = &ctx;
  TaskKind refit = TaskKind::per_step(
      {"gravity", "refit", "gravity"}, Stage::Gravity,
      [c](const tasks::Task& task) { refit_tree_group(*c, task.part); }, GravityTree::kRefitGroups);
  refit.reads_every_leaf = true;
  refit.before_phase = [c] { plan_tree_update(*c); };
  t.refit = tasks.add(std::move(refit));
  TaskKind tree = TaskKind::per_step({"gravity", "tree", "gravity"}, Stage::Gravity,
                                     [c](const tasks::Task&) { finish_tree(*c); });
  tree.reads_every_leaf = true;
  t.tree = tasks.add(std::move(tree));
  t.walk = tasks.add(TaskKind::leaf({"gravity", "walk", "gravity"}, Stage::Gravity,
                                    [c](const tasks::Task& task) { walk_cell(*c, task.ci); }));
  if (ctx.long_range) {
    TaskKind mesh = TaskKind::per_step({"gravity", "mesh", "gravity"}, Stage::Gravity,
                                       [c](const tasks::Task&) { compute_long_range(*c); });
    mesh.reads_every_leaf = true;
    t.mesh = tasks.add(std::move(mesh));
  }
  tasks.link([t, drift](GraphBuilder& g) {
    const int tree_task = g.step_tasks(t.tree).front();
    const int mesh_task = t.mesh >= 0 ? g.step_tasks(t.mesh).front() : -1;
    for (int r : g.step_tasks(t.refit)) g.depends(r, tree_task);
    for (int c : g.leaves()) {
      for (int r : g.step_tasks(t.refit)) g.depends(g.task(drift, c), r);
      g.depends(tree_task, g.task(t.walk, c));
      if (mesh_task >= 0) {
        g.depends(g.task(drift, c), mesh_task);
        g.depends(mesh_task, g.task(t.walk, c));
      }
    }
  });
  return t;
}

}  // namespace fountain::gravity
