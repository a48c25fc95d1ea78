#include "Executor.hpp"
#include "TbbHandOff.hpp"
#include "ThreadPinning.hpp"

#if defined(__x86_64__)
#include <x86intrin.h>
#endif
#include <tbb/info.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <fmt/format.h>

#include <atomic>
#include <exception>
#include <stdexcept>
#include <chrono>
#include <thread>
#include <algorithm>

namespace fountain::tasks {

namespace {
std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Per-task timestamps: the cycle counter where there is one (a few ns to read, against
// ~25 ns for the clock), converted to ns with the run's own wall time at the end.
std::int64_t now_ticks() {
#if defined(__x86_64__)
  return static_cast<std::int64_t>(__rdtsc());
#else
  return now_ns();
#endif
}

// Marks the thread as running a task's body, so that for_each_in_task can tell its own
// pieces (inside the task's time already) from those a helping thread runs.
class InTask {
 public:
  InTask() : outer_(flag()) { flag() = true; }
  ~InTask() { flag() = outer_; }
  InTask(const InTask&) = delete;
  InTask& operator=(const InTask&) = delete;
  static bool here() { return flag(); }

 private:
  static bool& flag() {
    thread_local bool in_task = false;
    return in_task;
  }
  bool outer_;
};
}  // namespace

Executor::Executor(int threads, std::vector<int> cpus)
    : threads_(threads > 0 ? threads : tbb::info::default_concurrency()),
      arena_(std::make_unique<tbb::task_arena>(threads_)),
      cpus_(std::move(cpus)) {
  if (cpus_.empty()) return;
  // TBB sizes its pool of workers from the affinity of the thread that first starts it: the
  // arena starts before the caller is pinned, or it would get no workers at all.
  arena_->initialize();
  // The caller's thread takes slot 0 when it enters the arena; its serial work between
  // graphs (a rank's rebuilds and exchanges) stays on that core too.
  pin_this_thread(cpus_[0]);
}

Executor::~Executor() = default;

void Executor::pin_here() const {
  // Checked as each job starts rather than by a TBB scheduler observer (whose registration
  // TBB frees only with the arena's internals, after LeakSanitizer has looked): a worker may
  // take another slot each time it joins, and the system call is made only when the CPU
  // for its slot changes.
  if (cpus_.empty()) return;
  const int slot = tbb::this_task_arena::current_thread_index();
  if (slot < 0) return;
  const int cpu = cpus_[static_cast<std::size_t>(slot) % cpus_.size()];
  thread_local int pinned_to = -1;
  if (pinned_to != cpu && pin_this_thread(cpu)) pinned_to = cpu;
}

void Executor::run(const TaskGraph& graph, const Runner& runner, std::vector<TaskRecord>* records,
                   const std::vector<int>* only, const Gates* gates) {
  const int n = graph.size();
  std::vector<std::atomic<int>> wait(static_cast<std::size_t>(n));
  // Which tasks take part: all of them, or the listed ones.
  const bool subset = only != nullptr;
  if (subset) {
    listed_.assign(static_cast<std::size_t>(n), 0);
    for (int t : *only) listed_[static_cast<std::size_t>(t)] = 1;
  }
  auto takes_part = [&](int t) { return !subset || listed_[static_cast<std::size_t>(t)]; };
  const int n_part = subset ? static_cast<int>(only->size()) : n;
  for (auto& w : wait) w.store(0, std::memory_order_relaxed);
  auto count_unlocks = [&](int t) {
    for (int u : graph.unlocks(t))
      if (takes_part(u)) wait[static_cast<std::size_t>(u)].fetch_add(1, std::memory_order_relaxed);
  };
  if (subset) {
    for (int t : *only) count_unlocks(t);
  } else {
    for (int t = 0; t < n; ++t) count_unlocks(t);
  }
  if (records) records->assign(static_cast<std::size_t>(n), TaskRecord{});
  // A gate is one more predecessor, released by a poll (open_gates below).
  std::vector<int> pending;
  if (gates)
    for (int t : gates->tasks)
      if (takes_part(t)) {
        wait[static_cast<std::size_t>(t)].fetch_add(1, std::memory_order_relaxed);
        pending.push_back(t);
      }
  const bool polling = !pending.empty();

  std::atomic<std::int64_t> busy{0};
  std::atomic<int> done{0};
  // Hand-offs between threads go through these atomics (and the wait counters), not only
  // through TBB's queues: so a task sees the set-up and its predecessors' writes, the caller
  // sees every task's writes, and ThreadSanitizer (TBB is not instrumented) sees it all too.
  std::atomic<bool> go{false};
  helped_ticks_.store(0, std::memory_order_relaxed);
  const std::int64_t k0 = now_ticks();
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  const std::int64_t t0 = now_ns();
  jobs_.store(0, std::memory_order_relaxed);
  // Polling for gates is done by the threads that run tasks, not by a thread of its own: a
  // busy thread polls between tasks once poll_every has passed, and a thread that would
  // otherwise idle keeps polling until a gate opens or work comes. A separate polling thread
  // woke every 20 us - 1 ms beside the workers; across two ranks on two cores its ~3,400
  // context switches per second per rank cost the workers ~25% more time in the SPH loops
  // (Sedov 250k, 2 ranks x 1 thread, perf), more than a late message ever did.
  // A busy thread's interval starts at kPollEvery, doubles after each poll that opens
  // nothing, up to kPollEveryMost, and starts again when one opens a gate: each poll tests
  // every waiting receive, and at a fixed 50 us the gaps between the tasks of a full Sedov
  // step (2 ranks x 1 thread) were ~10 ms of 270, 6-9 ms with the interval let grow, while
  // messages that do flow are still seen soon.
  constexpr std::int64_t kPollEvery = 50'000, kPollEveryMost = 1'000'000;  // ns
  std::atomic<int> waiting_gates{static_cast<int>(pending.size())};
  std::atomic<bool> poll_lock{false};     // one poll at a time: it owns `pending`
  std::atomic<bool> poller{false};        // a thread is in the idle polling loop
  std::atomic<std::int64_t> last_poll{now_ns()};
  std::int64_t poll_every = kPollEvery;   // guarded by poll_lock
  std::atomic<std::int64_t> due_every{kPollEvery};  // its value for threads deciding to poll

  tbb::task_arena& arena = *arena_;
  arena.execute([&] {
    tbb::task_group group;
    std::vector<int> roots;
    const std::vector<char>* urgent = gates != nullptr && !gates->urgent.empty() ? &gates->urgent : nullptr;
    auto is_urgent = [&](int t) { return urgent != nullptr && (*urgent)[static_cast<std::size_t>(t)] != 0; };
    // A lone thread with urgent tasks orders all its work itself (see `process`).
    const bool lone = threads_ == 1 && urgent != nullptr;
    constexpr int kAllRoots = -2;  // a lone thread's one job, which starts from every root
    // Runs task `first` and then, in this thread, whatever it readies, spawning the rest.
    std::function<void(int)> process;
    auto spawn = [&](int t) {
      jobs_.fetch_add(1, std::memory_order_acq_rel);
      group.run(SpawnedJob{&process, &go, t});
    };
    // Opens the gates whose condition holds (one poll for all of them: each MPI test call
    // drives the library's progress engine, so one call per waiting message would not do).
    // Returns how many gates opened (none when another thread holds the poll).
    std::vector<int> opened_now;
    auto open_gates = [&]() -> std::size_t {
      if (poll_lock.exchange(true, std::memory_order_acquire)) return 0;
      opened_now.clear();
      try {
        gates->poll(pending, opened_now);
      } catch (...) {
        if (!failed.exchange(true)) error = std::current_exception();
      }
      for (int t : opened_now) {
        pending.erase(std::find(pending.begin(), pending.end(), t));
        waiting_gates.fetch_sub(1, std::memory_order_acq_rel);
        if (wait[static_cast<std::size_t>(t)].fetch_sub(1, std::memory_order_acq_rel) == 1) spawn(t);
      }
      const std::size_t opened = opened_now.size();
      poll_every = opened > 0 ? kPollEvery : std::min(2 * poll_every, kPollEveryMost);
      last_poll.store(now_ns(), std::memory_order_relaxed);
      due_every.store(poll_every, std::memory_order_relaxed);
      poll_lock.store(false, std::memory_order_release);
      return opened;
    };
    auto poll_if_due = [&] {
      if (waiting_gates.load(std::memory_order_acquire) > 0 &&
          now_ns() - last_poll.load(std::memory_order_relaxed) >= due_every.load(std::memory_order_relaxed))
        open_gates();
    };
    // Called by each job as it ends: while gates wait and fewer jobs are under way than there
    // are threads (so that a thread would idle), this thread polls. It first yields between
    // polls (a message is often close), then naps, doubling, up to 1 ms: across more ranks
    // than cores, the rank with work gets the core. The outer loop closes the race with a job
    // that ended while this thread was leaving the loop.
    auto poll_while_idle = [&] {
      auto idle = [&] {
        return waiting_gates.load(std::memory_order_acquire) > 0 &&
               jobs_.load(std::memory_order_acquire) < threads_ && !failed.load();
      };
      while (idle()) {
        if (poller.exchange(true, std::memory_order_acq_rel)) return;  // another thread polls
        int quiet = 0;
        std::chrono::microseconds nap{50};
        while (idle()) {
          if (open_gates() > 0) {
            quiet = 0;
            nap = std::chrono::microseconds{50};
            continue;
          }
          if (++quiet < 200) {
            std::this_thread::yield();
          } else {
            std::this_thread::sleep_for(nap);
            nap = std::min(2 * nap, std::chrono::microseconds{1000});
          }
        }
        poller.store(false, std::memory_order_release);
      }
    };
    process = [&](int first) {
      pin_here();
      // Of what a thread holds it runs the urgent tasks first (those whose results other
      // ranks wait for), and a spawned task goes to another thread only if it is not urgent.
      // A lone thread has no one to hand work to, so with urgent tasks it keeps everything
      // it readies, the roots included, in its own lists, and picks the urgent first every
      // time: on Sedov 250k, 2 ranks x 1 thread, the time of the full steps beyond the busier
      // rank's tasks fell from 1.4-2.7 s to 1.3-2.0 s a run (three interleaved rounds).
      // Keeping the lists without putting the urgent first did worse than spawning (2.1-3.2 s):
      // that order ran the cells that feed other ranks late.
      std::vector<int> ready, hot;
      auto push = [&](int u) { (is_urgent(u) ? hot : ready).push_back(u); };
      if (first == kAllRoots) {
        for (auto r = roots.rbegin(); r != roots.rend(); ++r) push(*r);
      } else {
        ready.push_back(first);
      }
      std::int64_t my_busy = 0;
      int my_done = 0;
      while (!ready.empty() || !hot.empty()) {
        std::vector<int>& from = hot.empty() ? ready : hot;
        const int t = from.back();
        from.pop_back();
        if (t < 0) continue;  // the job that starts the polling: no task
        // Pairs with the release of the last predecessor's decrement.
        (void)wait[static_cast<std::size_t>(t)].load(std::memory_order_acquire);
        const Task& task = graph.task(t);
        ++my_done;
        if (task.active) {
          const std::int64_t s = now_ticks();
          try {
            const InTask in_task;
            runner(task);
          } catch (...) {
            // The first failure is kept and rethrown by the caller; what depends on it never runs.
            if (!failed.exchange(true)) error = std::current_exception();
            continue;
          }
          const std::int64_t e = now_ticks();
          my_busy += e - s;
          if (records)
            (*records)[static_cast<std::size_t>(t)] = {tbb::this_task_arena::current_thread_index(), s - k0, e - k0};
        }
        int keep = -1;
        for (int u : graph.unlocks(t)) {
          if (!takes_part(u)) continue;
          if (wait[static_cast<std::size_t>(u)].fetch_sub(1, std::memory_order_acq_rel) != 1) continue;
          if (!graph.task(u).active || lone) {
            push(u);  // an inactive task has no work: its unlocks are passed on here
          } else if (keep < 0) {
            keep = u;
          } else if (is_urgent(u) && !is_urgent(keep)) {
            spawn(keep);
            keep = u;
          } else {
            spawn(u);
          }
        }
        if (keep >= 0) push(keep);
        if (polling) poll_if_due();
      }
      busy.fetch_add(my_busy, std::memory_order_relaxed);
      jobs_.fetch_sub(1, std::memory_order_acq_rel);
      if (polling) poll_while_idle();
      // Adding to `done` is this job's last touch of the closure: the caller destroys it
      // after group.wait(), which ThreadSanitizer cannot see, and acquires `done` first.
      done.fetch_add(my_done, std::memory_order_acq_rel);
    };
    // Roots are collected before any runs: once tasks run, counters of others reach zero.
    auto root_if_free = [&](int t) {
      if (wait[static_cast<std::size_t>(t)].load(std::memory_order_relaxed) == 0) roots.push_back(t);
    };
    if (subset) {
      for (int t : *only) root_if_free(t);
    } else {
      for (int t = 0; t < n; ++t) root_if_free(t);
    }
    go.store(true, std::memory_order_release);
    if (!lone) {
      for (int t : roots) spawn(t);
    } else if (!roots.empty()) {
      spawn(kAllRoots);
    }
    // With gates and nothing free to run, a job that runs no task starts the polling.
    if (polling) spawn(-1);
    group.wait();
    (void)done.load(std::memory_order_acquire);  // every job's writes, before `process` goes
  });

  last_wall_ns_ = now_ns() - t0;
  const std::int64_t wall_ticks = now_ticks() - k0;
  const double ns_per_tick = wall_ticks > 0 ? static_cast<double>(last_wall_ns_) / static_cast<double>(wall_ticks) : 1.0;
  if (records)
    for (auto& r : *records) {
      r.start_ns = static_cast<std::int64_t>(static_cast<double>(r.start_ns) * ns_per_tick);
      r.end_ns = static_cast<std::int64_t>(static_cast<double>(r.end_ns) * ns_per_tick);
    }
  if (failed.load()) std::rethrow_exception(error);
  if (done.load(std::memory_order_acquire) != n_part)
    throw std::logic_error(fmt::format("task graph has a dependency cycle: {} of {} tasks could run", done.load(), n_part));
  last_busy_ns_ = static_cast<std::int64_t>(static_cast<double>(busy.load() + helped_ticks_.load()) * ns_per_tick);
}

}  // namespace fountain::tasks

namespace fountain::tasks {

void Executor::run_beside(const std::function<void()>& a, const std::function<void()>& b) {
  // A graph of two independent tasks: run() hands work and results between threads through
  // atomics that ThreadSanitizer sees (a bare tbb::parallel_invoke would not).
  TaskGraph pair;
  pair.add(0, 0, -1, -1);
  pair.add(0, 1, -1, -1);
  pair.finalize();
  run(pair, [&](const Task& t) { (t.ci == 0 ? a : b)(); });
}

void Executor::for_each(std::size_t n, const std::function<void(std::size_t)>& fn) {
  arena_->execute([&] {
    // Pinned once per piece of the range, not once per index.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
      pin_here();
      for (std::size_t k = r.begin(); k != r.end(); ++k) fn(k);
    });
  });
}

void Executor::for_each_in_task(std::size_t n, const std::function<void(std::size_t)>& fn) {
  // Pieces are claimed from one counter by the caller and by a helper job per other thread.
  // Jobs go through TBB's queue like the graph's (SpawnedJob), and everything they read or
  // write is ordered by these atomics, which ThreadSanitizer sees. Isolated, the caller's
  // wait runs only these jobs (a helper not yet started finds no piece left and returns).
  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<bool> go{false};
  std::function<void(int)> help = [&](int helper) {
    pin_here();
    const bool helping = !InTask::here();
    const std::int64_t s = helping ? now_ticks() : 0;
    std::size_t mine = 0;
    for (std::size_t k = next.fetch_add(1, std::memory_order_relaxed); k < n;
         k = next.fetch_add(1, std::memory_order_relaxed)) {
      fn(k);
      ++mine;
    }
    if (helping) helped_ticks_.fetch_add(now_ticks() - s, std::memory_order_relaxed);
    if (helper) jobs_.fetch_sub(1, std::memory_order_acq_rel);
    done.fetch_add(mine, std::memory_order_acq_rel);
  };
  tbb::this_task_arena::isolate([&] {
    tbb::task_group group;
    go.store(true, std::memory_order_release);
    // The helpers count as jobs, so that an idle thread polling for gates makes way for them.
    for (int h = 1; h < threads_ && static_cast<std::size_t>(h) < n; ++h) {
      jobs_.fetch_add(1, std::memory_order_acq_rel);
      group.run(SpawnedJob{&help, &go, 1});
    }
    help(0);
    group.wait();
  });
  (void)done.load(std::memory_order_acquire);  // the helpers' writes, before the caller goes on
}

}  // namespace fountain::tasks
