#include "feedback/FeedbackTasks.hpp"

namespace fountain::feedback {

FeedbackTaskTypes register_tasks(StepTasks& tasks, StepContext& ctx, FeedbackState& fb, int star_formation_done) {
  FeedbackTaskTypes t;
  StepContext* c = &ctx;
  FeedbackState* f = &fb;
  TaskKind search = TaskKind::leaf({"feedback", "search", "feedback"}, Stage::Feedback,
                                   [c, f](const tasks::Task& task) { find_hot_neighbours(*c, *f, task.ci); });
  search.gas_leaves_only = true;
  t.search = tasks.add(std::move(search));
  t.apply = tasks.add(TaskKind::per_step({"feedback", "apply", "feedback"}, Stage::Feedback,
                                         [c, f](const tasks::Task&) { apply_feedback(*c, *f, c->space.leaves()); }));
  // Every leaf's search reads neighbours as star formation left them, in any leaf; one task
  // then hands feedback out in a fixed order, before any leaf cools or opens its next step.
  tasks.link([t, star_formation_done](GraphBuilder& g) {
    const int done = g.step_tasks(star_formation_done).front();
    const int apply = g.step_tasks(t.apply).front();
    // Direct, so the order holds on a rank that lists no search in between.
    g.depends(done, apply);
    for (int c : g.leaves()) {
      const int search = g.task(t.search, c);
      if (search < 0) continue;
      g.depends(done, search);
      g.depends(search, apply);
      g.depends(apply, g.first_after(Stage::Feedback, c));
    }
  });
  return t;
}

}  // namespace fountain::feedback
