// The job object the executor gives TBB for each spawned task, kept in its own file so the
// ThreadSanitizer suppression that concerns it can name it precisely.
#pragma once
#include <atomic>
#include <functional>

namespace fountain::tasks {

// TBB hands this object from the spawning thread to the running one through its own queue,
// which ThreadSanitizer cannot see (libtbb is not instrumented): reading these three members
// is the one access it cannot find ordered, so .ci/tsan.supp names this file. Everything
// after the acquire of `go` is ordered by the executor's own atomics.
struct SpawnedJob {
  std::function<void(int)>* process;
  std::atomic<bool>* go;
  int task;
  __attribute__((noinline)) void operator()() const {
    (void)go->load(std::memory_order_acquire);
    (*process)(task);
  }
};

}  // namespace fountain::tasks
