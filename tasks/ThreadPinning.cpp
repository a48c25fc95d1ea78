#include "ThreadPinning.hpp"

#include <sched.h>

namespace fountain::tasks {

std::vector<int> allowed_cpus() {
  std::vector<int> cpus;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return cpus;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  return cpus;
}

std::vector<int> pinning_plan(const std::vector<int>& allowed, int threads, int local_rank, int local_ranks) {
  std::vector<int> plan;
  if (allowed.empty() || threads <= 0) return plan;
  const std::size_t n = allowed.size();
  const bool shared = local_ranks > 1 && n > static_cast<std::size_t>(threads);
  const std::size_t first = shared ? static_cast<std::size_t>(local_rank) * static_cast<std::size_t>(threads) : 0;
  for (int t = 0; t < threads; ++t) plan.push_back(allowed[(first + static_cast<std::size_t>(t)) % n]);
  return plan;
}

bool pin_this_thread(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE) return false;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return sched_setaffinity(0, sizeof(set), &set) == 0;
}

}  // namespace fountain::tasks
