// Which cores a process's task threads are pinned to, from its affinity mask and its place among the ranks on its node.
#pragma once
#include <vector>

namespace fountain::tasks {

// The CPUs this process may run on (its affinity mask, ascending); empty where it cannot be read.
std::vector<int> allowed_cpus();

// The CPU for each of `threads` task threads (index = the thread's slot in the executor's
// arena). A mask no wider than `threads` was set for this rank alone (mpirun --bind-to core,
// taskset): its threads take its CPUs in turn. A wider one is taken to be shared by the
// ranks on the node (mpirun --bind-to none, or a socket per few ranks), and local rank r
// starts r x threads CPUs in (wrapping round), so that ranks' threads land on different
// cores where there are enough. Empty (no pinning) when the mask is unknown.
std::vector<int> pinning_plan(const std::vector<int>& allowed, int threads, int local_rank, int local_ranks);

// Binds the calling thread to one CPU; false (and nothing changed) where the system refuses.
bool pin_this_thread(int cpu);

}  // namespace fountain::tasks
