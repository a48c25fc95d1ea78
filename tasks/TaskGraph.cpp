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

void TaskGraph::depends(int before, int after) {
  if (before == after) return;
  tasks_[static_cast<std::size_t>(before)].unlocks.push_back(after);
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
  for (auto& t : tasks_) {
    std::sort(t.unlocks.begin(), t.unlocks.end());
    t.unlocks.erase(std::unique(t.unlocks.begin(), t.unlocks.end()), t.unlocks.end());
  }
  finalized_ = true;
}

std::size_t TaskGraph::num_dependencies() const {
  std::size_t n = 0;
  for (const auto& t : tasks_) n += t.unlocks.size();
  return n;
}

}  // namespace fountain::tasks
