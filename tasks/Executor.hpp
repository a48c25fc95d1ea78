// Runs a TaskGraph on TBB worker threads, honouring every dependency, and records a timeline.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <tbb/task_arena.h>

#include "TaskGraph.hpp"


namespace fountain::tasks {

// What happened to one task in one run: who ran it and when (ns since the run began).
struct TaskRecord {
  std::int32_t thread = -1;
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
};

class Executor {
 public:
  // threads <= 0: as many as TBB sees. With `cpus` (one per thread, ThreadPinning.hpp), the
  // thread in slot k of the executor's arena runs its work on cpus[k] only: the caller's
  // thread from construction on (it takes slot 0), each worker from its first job.
  explicit Executor(int threads, std::vector<int> cpus = {});
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  int threads() const { return threads_; }

  using Runner = std::function<void(const Task&)>;

  // Tasks that also wait for something outside the graph, such as a message from another
  // rank: each runs only once `poll` has named it (and its predecessors are done). `poll`
  // is handed the tasks still waiting and appends those whose condition now holds. The
  // threads that run tasks call it, one at a time (any of them, so it must not care which):
  // between tasks at most every 50 us, and without pause while no task can run. No thread
  // ever blocks on a message, and no thread beyond `threads` wakes to poll.
  struct Gates {
    std::vector<int> tasks;
    std::function<void(std::span<const int> waiting, std::vector<int>& opened)> poll;
    // Per task (empty: none): what to run first when a thread has a choice, here the tasks
    // that lead to sends, so that other ranks get their messages early.
    std::vector<char> urgent;
  };

  // Runs every active task of `graph` once its predecessors have finished; inactive tasks
  // pass their unlocks on at once. Fills `records` (one per task) when it is non-null.
  // An exception thrown by a task is rethrown here after the running tasks have stopped.
  //
  // With `only`, just those tasks run and every other task is ignored, dependencies through
  // it included: the cost is then that of the listed tasks, not of the whole graph. The
  // caller promises that every ordering that matters between listed tasks is a direct
  // dependency (or a chain of listed tasks).
  void run(const TaskGraph& graph, const Runner& runner, std::vector<TaskRecord>* records = nullptr,
           const std::vector<int>* only = nullptr, const Gates* gates = nullptr);

  // Runs fn(0..n-1) in parallel on this executor's threads (for simple per-cell sweeps).
  void for_each(std::size_t n, const std::function<void(std::size_t)>& fn);

  // The same from inside a running task, so that a thread with nothing else to do helps a
  // task that holds up the step. The calling thread takes only this loop's pieces while it
  // waits (never another task, which would run inside this one's record); a helping
  // thread's time counts as busy. fn(k) must not depend on which thread runs it.
  void for_each_in_task(std::size_t n, const std::function<void(std::size_t)>& fn);

  // Runs a and b at once on this executor's threads (one after the other on one thread) and
  // returns when both are done; they must not touch the same data.
  void run_beside(const std::function<void()>& a, const std::function<void()>& b);

  // Wall time of the last run, and the time spent inside tasks summed over threads (ns).
  std::int64_t last_wall_ns() const { return last_wall_ns_; }
  std::int64_t last_busy_ns() const { return last_busy_ns_; }

 private:
  int threads_;
  std::unique_ptr<tbb::task_arena> arena_;
  std::vector<int> cpus_;  // by arena slot; empty: threads float
  void pin_here() const;
  std::vector<char> listed_;  // scratch for `only`: which tasks are listed
  std::int64_t last_wall_ns_ = 0;
  std::int64_t last_busy_ns_ = 0;
  std::atomic<std::int64_t> helped_ticks_{0};  // for_each_in_task pieces run outside any task
  std::atomic<int> jobs_{0};  // jobs of the current run (and their helpers) spawned, not yet finished
};

}  // namespace fountain::tasks
