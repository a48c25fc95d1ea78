#include "star_formation/StarFormationTasks.hpp"

namespace fountain::star_formation {

StarFormationTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, const StarFormationState& sf,
                                      feedback::FeedbackState& fb) {
  StarFormationTaskTypes t;
  StepContext* c = &ctx;
  const StarFormationState* s = &sf;
  feedback::FeedbackState* f = &fb;
  TaskKind form = TaskKind::leaf({"star_formation", "", "star_formation"}, Stage::StarFormation,
                                 [c, s, f](const tasks::Task& task) { form_stars(*c, *s, *f, task.ci); });
  form.gas_leaves_only = true;
  t.form = tasks.add(std::move(form));
  t.done = tasks.add(TaskKind::per_step({"star_formation", "done", "star_formation"}, Stage::StarFormation,
                                        [](const tasks::Task&) {}));
  tasks.link([t](GraphBuilder& g) {
    const int done = g.step_tasks(t.done).front();
    for (int c : g.leaves()) g.depends(g.task(t.form, c), done);  // none for a leaf without gas
  });
  return t;
}

}  // namespace fountain::star_formation
