// A dependency graph of typed tasks over cells; knows no physics, only tasks and resources.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace fountain::tasks {

// Task types are registered once, by whoever builds graphs; the graph stores only indices.
struct TaskTypeInfo {
  std::string name;      // e.g. "density"
  std::string subtype;   // e.g. "self" or "pair"; may be empty
  std::string category;  // coarse group for reports: "hydro", "gravity", "integration", ...
};

class TaskTypeRegistry {
 public:
  int add(TaskTypeInfo info) {
    types_.push_back(std::move(info));
    return static_cast<int>(types_.size()) - 1;
  }
  const TaskTypeInfo& operator[](int t) const { return types_[static_cast<std::size_t>(t)]; }
  int size() const { return static_cast<int>(types_.size()); }
  std::string full_name(int t) const {
    const auto& i = (*this)[t];
    return i.subtype.empty() ? i.name : i.name + "_" + i.subtype;
  }

 private:
  std::vector<TaskTypeInfo> types_;
};

struct Task {
  int type = -1;
  int ci = -1;          // the cell the task works on (and writes, if `writes` says so)
  int cj = -1;          // the other cell of a pair task, read only
  int writes = -1;      // the one resource (cell) the task writes; -1 for none
  int part = -1;        // of a job shared out over several tasks of one type: which share
  bool active = true;   // skipped tasks count as done at once
};

// Tasks plus dependencies. Every task that writes a resource is chained, in insertion
// order, after the previous task writing the same resource: no two tasks ever write one
// cell at once, and each cell's updates always happen in the same order, so floating-point
// sums are reproducible whatever the number of threads.
class TaskGraph {
 public:
  // Room for `tasks` tasks and `dependencies` explicit dependencies (saves regrowth).
  void reserve(std::size_t tasks, std::size_t dependencies);
  int add(int type, int ci, int cj = -1, int writes = -1);
  // `after` may start only when `before` has finished.
  void depends(int before, int after);
  // Adds the per-resource chains and packs every task's unlocks into one array; call once
  // after the last add().
  void finalize();

  // The tasks that wait for task t (after finalize), sorted, without repeats.
  std::span<const int> unlocks(int t) const {
    const auto b = unlock_offsets_[static_cast<std::size_t>(t)], e = unlock_offsets_[static_cast<std::size_t>(t) + 1];
    return {unlock_targets_.data() + b, e - b};
  }

  const std::vector<Task>& tasks() const { return tasks_; }
  Task& task(int t) { return tasks_[static_cast<std::size_t>(t)]; }
  const Task& task(int t) const { return tasks_[static_cast<std::size_t>(t)]; }
  int size() const { return static_cast<int>(tasks_.size()); }
  bool finalized() const { return finalized_; }
  void set_all_active(bool a) {
    for (auto& t : tasks_) t.active = a;
  }
  std::size_t num_dependencies() const;

  // Marks (1) the tasks in `targets` and every task that leads to one of them through tasks
  // marked in `listed` (indexed by task), that is what must finish before they can start.
  // The predecessor lists are built on the first call after finalize.
  std::vector<char> ancestors(std::span<const int> targets, const std::vector<char>& listed);

 private:
  std::vector<Task> tasks_;
  std::vector<std::pair<int, int>> edges_;   // (before, after) until finalize
  std::vector<std::size_t> unlock_offsets_;  // CSR: unlocks of t are targets[offsets[t], offsets[t+1])
  std::vector<int> unlock_targets_;
  std::vector<std::size_t> wait_offsets_;  // CSR of the predecessors, built by ancestors()
  std::vector<int> wait_sources_;
  bool finalized_ = false;
};

}  // namespace fountain::tasks
