#include "TaskGraph.hpp"

#include <algorithm>
#include <stdexcept>

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
  // A task the caller never added (-1 from a lookup) would corrupt the counting sort below.
  if (before < 0 || after < 0 || before >= size() || after >= size())
    throw std::logic_error("TaskGraph::depends(" + std::to_string(before) + ", " + std::to_string(after) +
                           "): no such task (" + std::to_string(size()) + " tasks)");
  edges_.emplace_back(before, after);
}

void TaskGraph::finalize() {
  if (finalized_) return;
  wait_offsets_.clear();
  wait_sources_.clear();
  // Chain the writers of each resource in insertion order.
  int resources = 0;
  for (const Task& t : tasks_) resources = std::max(resources, t.writes + 1);
  std::vector<int> last_writer(static_cast<std::size_t>(resources), -1);
  for (int t = 0; t < size(); ++t) {
    const int r = tasks_[static_cast<std::size_t>(t)].writes;
    if (r < 0) continue;
    int& last = last_writer[static_cast<std::size_t>(r)];
    if (last >= 0) depends(last, t);
    last = t;
  }
  // Bucket the edges by their first task (a counting sort: the engine rebuilds its graph
  // often, and a comparison sort of all edges was a sixth of a collapsing sphere's run),
  // then drop repeats from each task's list by marking what it already unlocks (sorting the
  // lists instead was still 1% of that run). Lists keep the order the edges were added in.
  const std::size_t n = tasks_.size();
  std::vector<std::size_t> start(n + 1, 0);
  for (const auto& e : edges_) ++start[static_cast<std::size_t>(e.first) + 1];
  for (std::size_t t = 0; t < n; ++t) start[t + 1] += start[t];
  std::vector<int> targets(edges_.size());
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (const auto& e : edges_) targets[fill[static_cast<std::size_t>(e.first)]++] = e.second;
  }
  std::vector<std::pair<int, int>>().swap(edges_);
  unlock_offsets_.assign(n + 1, 0);
  unlock_targets_.clear();
  unlock_targets_.reserve(targets.size());
  std::vector<int> listed_by(n, -1);  // the last task whose list took this one
  for (std::size_t t = 0; t < n; ++t) {
    for (std::size_t k = start[t]; k < start[t + 1]; ++k) {
      const int u = targets[k];
      if (listed_by[static_cast<std::size_t>(u)] == static_cast<int>(t)) continue;
      listed_by[static_cast<std::size_t>(u)] = static_cast<int>(t);
      unlock_targets_.push_back(u);
    }
    unlock_offsets_[t + 1] = unlock_targets_.size();
  }
  finalized_ = true;
}

std::size_t TaskGraph::num_dependencies() const { return unlock_targets_.size(); }

std::vector<char> TaskGraph::ancestors(std::span<const int> targets, const std::vector<char>& listed) {
  if (!finalized_) throw std::logic_error("TaskGraph::ancestors before finalize");
  const std::size_t n = tasks_.size();
  if (wait_offsets_.size() != n + 1) {
    wait_offsets_.assign(n + 1, 0);
    for (int u : unlock_targets_) ++wait_offsets_[static_cast<std::size_t>(u) + 1];
    for (std::size_t t = 0; t < n; ++t) wait_offsets_[t + 1] += wait_offsets_[t];
    wait_sources_.resize(unlock_targets_.size());
    std::vector<std::size_t> fill(wait_offsets_.begin(), wait_offsets_.end() - 1);
    for (std::size_t t = 0; t < n; ++t)
      for (int u : unlocks(static_cast<int>(t))) wait_sources_[fill[static_cast<std::size_t>(u)]++] = static_cast<int>(t);
  }
  std::vector<char> marked(n, 0);
  std::vector<int> stack(targets.begin(), targets.end());
  for (int t : targets) marked[static_cast<std::size_t>(t)] = 1;
  while (!stack.empty()) {
    const std::size_t t = static_cast<std::size_t>(stack.back());
    stack.pop_back();
    for (std::size_t k = wait_offsets_[t]; k < wait_offsets_[t + 1]; ++k) {
      const auto p = static_cast<std::size_t>(wait_sources_[k]);
      if (marked[p] || !listed[p]) continue;
      marked[p] = 1;
      stack.push_back(static_cast<int>(p));
    }
  }
  return marked;
}

}  // namespace fountain::tasks
