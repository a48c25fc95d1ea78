#include "TaskGraph.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace fountain::tasks {

int TaskGraph::add(int type, int ci, int cj, int writes) {
  if (finalized_) throw std::logic_error("TaskGraph::add after finalize");
  Task t;
  t.type = type;
  t.ci = ci;
  t.cj = cj;
  t.writes = writes;
  tasks_.push_back(std::move(t));
  return static_cast<int>(tasks_.size()) - 1;
}

void TaskGraph::reserve(std::size_t tasks, std::size_t dependencies) {
  tasks_.reserve(tasks);
  edges_.reserve(dependencies);
}

void TaskGraph::depends(int before, int after) {
  if (before == after) return;
  edges_.emplace_back(before, after);
}

void TaskGraph::finalize() {
  if (finalized_) return;
  std::unordered_map<int, int> last_writer;
  for (int t = 0; t < size(); ++t) {
    const int r = tasks_[static_cast<std::size_t>(t)].writes;
    if (r < 0) continue;
    auto it = last_writer.find(r);
    if (it != last_writer.end()) depends(it->second, t);
    last_writer[r] = t;
  }
  std::sort(edges_.begin(), edges_.end());
  edges_.erase(std::unique(edges_.begin(), edges_.end()), edges_.end());
  unlock_offsets_.assign(tasks_.size() + 1, 0);
  for (const auto& [before, after] : edges_) ++unlock_offsets_[static_cast<std::size_t>(before) + 1];
  for (std::size_t t = 0; t < tasks_.size(); ++t) unlock_offsets_[t + 1] += unlock_offsets_[t];
  unlock_targets_.resize(edges_.size());
  for (std::size_t k = 0; k < edges_.size(); ++k) unlock_targets_[k] = edges_[k].second;  // sorted by (before, after)
  std::vector<std::pair<int, int>>().swap(edges_);
  finalized_ = true;
}

std::size_t TaskGraph::num_dependencies() const { return unlock_targets_.size(); }

}  // namespace fountain::tasks
