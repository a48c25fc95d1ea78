// Tests of the task-graph writers (dependency CSV, DOT, timeline CSV) and of the ordering
// guarantees of tasks::Executor that the timelines rely on.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <span>
#include <mutex>
#include <thread>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/Error.hpp"
#include "tasks/Executor.hpp"
#include "tasks/TaskGraph.hpp"
#include "tasks/TaskGraphDump.hpp"
#include "tasks/ThreadPinning.hpp"

#include <sched.h>
#include <tbb/task_arena.h>

namespace fs = std::filesystem;
using fountain::tasks::Executor;
using fountain::tasks::Task;
using fountain::tasks::TaskGraph;
using fountain::tasks::TaskRecord;
using fountain::tasks::TaskTypeRegistry;

namespace {

// A fresh directory under the system temp dir, removed again at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::random_device rd;
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    for (int attempt = 0; attempt < 100; ++attempt) {
      path_ = fs::temp_directory_path() /
              ("fountain_task_dumps_" + std::to_string(stamp) + "_" + std::to_string(rd()));
      if (fs::create_directory(path_)) return;
    }
    throw std::runtime_error("cannot create a temporary directory");
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.is_open()) << path;
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> f;
  std::string cur;
  for (char c : line) {
    if (c == ',') {
      f.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  f.push_back(cur);
  return f;
}

int column(const std::vector<std::string>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  return it == header.end() ? -1 : static_cast<int>(it - header.begin());
}

void spin_for(std::chrono::microseconds d) {
  const auto until = std::chrono::steady_clock::now() + d;
  while (std::chrono::steady_clock::now() < until) {
  }
}

// Index of `t` in `g` (the runner only gets the task).
int index_of(const TaskGraph& g, const Task& t) { return static_cast<int>(&t - g.tasks().data()); }

// A small hydro-like step on three cells:
//   density_self on cells 0,1,2; density_pair on (0,1) and (1,2); kick on 0,1,2;
//   one "timer" task with no dependencies at all; and a registered "gravity" type without tasks.
struct SmallStep {
  TaskTypeRegistry types;
  TaskGraph graph;
  int self_t = -1, pair_t = -1, kick_t = -1, grav_t = -1, timer_t = -1;
  int s0 = -1, s1 = -1, s2 = -1, p01 = -1, p12 = -1, k0 = -1, k1 = -1, k2 = -1, timer = -1;

  SmallStep() {
    self_t = types.add({"density", "self", "hydro"});
    pair_t = types.add({"density", "pair", "hydro"});
    kick_t = types.add({"kick", "", "integration"});
    grav_t = types.add({"grav", "self", "gravity"});
    timer_t = types.add({"timer", "", "misc"});

    s0 = graph.add(self_t, 0, -1, 0);
    s1 = graph.add(self_t, 1, -1, 1);
    s2 = graph.add(self_t, 2, -1, 2);
    p01 = graph.add(pair_t, 0, 1, 0);  // chained after s0 (writes cell 0)
    p12 = graph.add(pair_t, 1, 2, 1);  // chained after s1 (writes cell 1)
    graph.depends(s1, p01);            // reads cell 1
    graph.depends(s2, p12);            // reads cell 2
    k0 = graph.add(kick_t, 0, -1, 0);  // chained after p01
    k1 = graph.add(kick_t, 1, -1, 1);  // chained after p12
    k2 = graph.add(kick_t, 2, -1, 2);  // chained after s2
    graph.depends(p01, k1);
    timer = graph.add(timer_t, -1);
    graph.finalize();
  }
};

}  // namespace

TEST(TaskDumps, SmallStepHasTheExpectedDependencies) {
  SmallStep s;
  EXPECT_EQ(s.graph.size(), 9);
  EXPECT_EQ(s.graph.num_dependencies(), 8u);
}

TEST(TaskDumps, DependencyCsvMatchesSwiftFormat) {
  SmallStep s;
  TempDir dir;
  const std::string path = dir.file("dependency_graph_0.csv");
  fountain::tasks::write_dependency_csv(s.graph, s.types, path);

  const auto lines = read_lines(path);
  ASSERT_GE(lines.size(), 2u);
  // SWIFT's plot_task_dependencies.py takes the first line, when it starts with '#', as the version.
  ASSERT_FALSE(lines[0].empty());
  EXPECT_EQ(lines[0].substr(0, 2), "# ");
  EXPECT_EQ(lines[1],
            "task_in,task_out,implicit_in,implicit_out,mpi_in,mpi_out,cluster_in,cluster_out,"
            "number_link,number_rank,task_in_is_top,task_in_is_hydro_super,task_in_is_grav_super,"
            "task_out_is_top,task_out_is_hydro_super,task_out_is_grav_super,cell_has_active_task");
  const auto header = split_csv(lines[1]);
  ASSERT_EQ(header.size(), 17u);

  // Three type-to-type links plus one row for the timer, which neither unlocks nor waits.
  ASSERT_EQ(lines.size(), 2u + 4u);
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> rows;
  std::size_t total_links = 0;
  for (std::size_t i = 2; i < lines.size(); ++i) {
    const auto f = split_csv(lines[i]);
    ASSERT_EQ(f.size(), header.size()) << lines[i];
    const auto key = std::make_pair(f[0], f[1]);
    EXPECT_EQ(rows.count(key), 0u) << "duplicate row " << lines[i];
    rows[key] = f;
    total_links += std::stoul(f[static_cast<std::size_t>(column(header, "number_link"))]);
  }
  EXPECT_EQ(total_links, s.graph.num_dependencies());

  const auto link = static_cast<std::size_t>(column(header, "number_link"));
  const auto cl_in = static_cast<std::size_t>(column(header, "cluster_in"));
  const auto cl_out = static_cast<std::size_t>(column(header, "cluster_out"));
  const auto rank = static_cast<std::size_t>(column(header, "number_rank"));
  const auto impl = static_cast<std::size_t>(column(header, "implicit_in"));
  const auto mpi = static_cast<std::size_t>(column(header, "mpi_out"));

  const std::pair<std::string, std::string> sp{"density_self", "density_pair"};
  const std::pair<std::string, std::string> pk{"density_pair", "kick"};
  const std::pair<std::string, std::string> sk{"density_self", "kick"};
  const std::pair<std::string, std::string> tn{"timer", "task_unlocks_nothing"};
  ASSERT_EQ(rows.count(sp), 1u);
  ASSERT_EQ(rows.count(pk), 1u);
  ASSERT_EQ(rows.count(sk), 1u);
  ASSERT_EQ(rows.count(tn), 1u);
  EXPECT_EQ(rows[sp][link], "4");
  EXPECT_EQ(rows[pk][link], "3");
  EXPECT_EQ(rows[sk][link], "1");
  EXPECT_EQ(rows[tn][link], "0");

  EXPECT_EQ(rows[sp][cl_in], "hydro");
  EXPECT_EQ(rows[sp][cl_out], "hydro");
  EXPECT_EQ(rows[pk][cl_out], "integration");
  EXPECT_EQ(rows[tn][cl_in], "misc");
  EXPECT_EQ(rows[tn][cl_out], "None");
  for (const auto& [key, f] : rows) {
    EXPECT_EQ(f[rank], "1") << key.first;
    EXPECT_EQ(f[impl], "0") << key.first;
    EXPECT_EQ(f[mpi], "0") << key.first;
    // The type without tasks never appears.
    EXPECT_NE(key.first, "grav_self");
    EXPECT_NE(key.second, "grav_self");
  }
}

TEST(TaskDumps, DotHasOneNodePerUsedTypeAndCountedEdges) {
  SmallStep s;
  TempDir dir;
  const std::string path = dir.file("tasks.dot");
  fountain::tasks::write_dot(s.graph, s.types, path);
  const std::string dot = read_all(path);

  EXPECT_EQ(dot.rfind("digraph", 0), 0u) << dot;
  EXPECT_NE(dot.find('}'), std::string::npos);
  EXPECT_NE(dot.find("\"density_self\" [label=\"density_self\\n3 tasks\""), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"density_pair\" [label=\"density_pair\\n2 tasks\""), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"kick\" [label=\"kick\\n3 tasks\""), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"timer\" [label=\"timer\\n1 tasks\""), std::string::npos) << dot;
  EXPECT_EQ(dot.find("grav_self"), std::string::npos) << dot;

  EXPECT_NE(dot.find("\"density_self\" -> \"density_pair\" [label=\"4\"]"), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"density_pair\" -> \"kick\" [label=\"3\"]"), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"density_self\" -> \"kick\" [label=\"1\"]"), std::string::npos) << dot;
  std::size_t arrows = 0;
  for (std::size_t p = dot.find("->"); p != std::string::npos; p = dot.find("->", p + 2)) ++arrows;
  EXPECT_EQ(arrows, 3u);

  // Nodes of one category share a colour; different categories get different ones.
  auto colour = [&](const std::string& node) {
    const auto p = dot.find("\"" + node + "\" [label=");
    if (p == std::string::npos) return std::string();
    const auto c = dot.find("fillcolor=\"", p);
    const auto e = dot.find('"', c + 11);
    return dot.substr(c + 11, e - c - 11);
  };
  EXPECT_FALSE(colour("density_self").empty());
  EXPECT_EQ(colour("density_self"), colour("density_pair"));
  EXPECT_NE(colour("density_self"), colour("kick"));
  EXPECT_NE(colour("kick"), colour("timer"));
}

TEST(TaskDumps, TimelineHasOneRowPerActiveTask) {
  SmallStep s;
  s.graph.task(s.k2).active = false;

  Executor exec(2);
  std::vector<TaskRecord> records;
  std::atomic<int> ran{0};
  exec.run(
      s.graph,
      [&](const Task&) {
        spin_for(std::chrono::microseconds(50));
        ++ran;
      },
      &records);
  ASSERT_EQ(ran.load(), 8);
  ASSERT_EQ(records.size(), 9u);
  EXPECT_EQ(records[static_cast<std::size_t>(s.k2)].thread, -1);

  TempDir dir;
  const std::string path = dir.file("timeline_step7_rank0.csv");
  fountain::tasks::write_timeline_csv(s.graph, s.types, records, /*rank=*/0, /*step=*/7, path);
  const auto lines = read_lines(path);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "# fountain task timeline: step=7 rank=0");
  EXPECT_EQ(lines[1], "type,subtype,category,ci,cj,rank,thread,start_ns,end_ns");
  ASSERT_EQ(lines.size(), 2u + 8u);

  std::map<std::string, int> per_type;
  for (std::size_t i = 2; i < lines.size(); ++i) {
    const auto f = split_csv(lines[i]);
    ASSERT_EQ(f.size(), 9u) << lines[i];
    per_type[f[1].empty() ? f[0] : f[0] + "_" + f[1]]++;
    EXPECT_EQ(f[5], "0");
    const int thread = std::stoi(f[6]);
    EXPECT_GE(thread, 0);
    EXPECT_LT(thread, 2);
    const long long start = std::stoll(f[7]);
    const long long end = std::stoll(f[8]);
    EXPECT_GE(start, 0);
    EXPECT_LE(start, end) << lines[i];
    if (f[0] == "density" && f[1] == "pair") {
      EXPECT_NE(f[4], "-1");
    }
    if (f[0] == "kick") {
      EXPECT_EQ(f[2], "integration");
    }
  }
  EXPECT_EQ(per_type["density_self"], 3);
  EXPECT_EQ(per_type["density_pair"], 2);
  EXPECT_EQ(per_type["kick"], 2);  // k2 was inactive
  EXPECT_EQ(per_type["timer"], 1);
  EXPECT_EQ(per_type.count("grav_self"), 0u);
}

TEST(TaskDumps, UnwritablePathThrowsInputErrorNamingIt) {
  SmallStep s;
  TempDir dir;
  const std::string bad = dir.file("no_such_dir/out.csv");
  std::vector<TaskRecord> records(static_cast<std::size_t>(s.graph.size()));
  auto expect_names_path = [&](auto&& call) {
    try {
      call();
      ADD_FAILURE() << "no exception for " << bad;
    } catch (const fountain::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  };
  expect_names_path([&] { fountain::tasks::write_dependency_csv(s.graph, s.types, bad); });
  expect_names_path([&] { fountain::tasks::write_dot(s.graph, s.types, bad); });
  expect_names_path([&] { fountain::tasks::write_timeline_csv(s.graph, s.types, records, 0, 0, bad); });
}

TEST(Executor, ChainOnOneResourceRunsInInsertionOrder) {
  TaskTypeRegistry types;
  const int work = types.add({"work", "", "test"});
  const int other = types.add({"other", "", "test"});
  TaskGraph g;
  constexpr int n = 200;
  std::vector<int> chain;
  for (int i = 0; i < n; ++i) {
    chain.push_back(g.add(work, 0, -1, /*writes=*/0));
    g.add(other, 1 + i, -1, /*writes=*/1 + i);  // independent work to keep both threads busy
  }
  g.finalize();

  Executor exec(2);
  for (int repeat = 0; repeat < 20; ++repeat) {
    // Only chained tasks touch `seen`, and they never overlap, so it needs no lock. The relaxed
    // flag only turns a broken executor's overlap into a clean failure instead of a corrupted
    // heap; it adds no ordering, so a thread sanitizer still checks the executor's own.
    std::vector<int> seen;
    std::atomic<bool> inside{false};
    std::atomic<int> overlaps{0};
    exec.run(g, [&](const Task& t) {
      if (t.type != work) return;
      if (inside.exchange(true, std::memory_order_relaxed)) {
        overlaps.fetch_add(1, std::memory_order_relaxed);
        return;
      }
      seen.push_back(index_of(g, t));
      inside.store(false, std::memory_order_relaxed);
    });
    EXPECT_EQ(overlaps.load(), 0) << "two tasks writing one resource ran at once";
    EXPECT_EQ(seen, chain);
  }
}

TEST(Executor, EveryActiveTaskRunsExactlyOnce) {
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  TaskGraph g;
  // Short chains on a few resources plus some free tasks: many tasks become ready while the
  // first ones are still being spawned.
  for (int i = 0; i < 2000; ++i) g.add(ty, i, -1, i % 3 == 0 ? -1 : i % 7);
  g.finalize();
  for (int i = 0; i < g.size(); i += 11) g.task(i).active = false;

  Executor exec(2);
  for (int repeat = 0; repeat < 20; ++repeat) {
    std::vector<std::atomic<int>> runs(static_cast<std::size_t>(g.size()));
    for (auto& r : runs) r.store(0);
    std::vector<TaskRecord> rec;
    exec.run(g, [&](const Task& t) { runs[static_cast<std::size_t>(index_of(g, t))].fetch_add(1); }, &rec);
    for (int i = 0; i < g.size(); ++i) {
      const bool active = g.task(i).active;
      ASSERT_EQ(runs[static_cast<std::size_t>(i)].load(), active ? 1 : 0) << "task " << i << ", repeat " << repeat;
      EXPECT_EQ(rec[static_cast<std::size_t>(i)].thread >= 0, active) << "task " << i;
    }
  }
}

TEST(ThreadPinning, RanksSharingAMaskTakeTheirOwnCoresAndABoundRankKeepsItsOwn) {
  using fountain::tasks::pinning_plan;
  using V = std::vector<int>;
  // mpirun --bind-to none on two cores: one thread per rank, each on its own core.
  EXPECT_EQ(pinning_plan({0, 1}, 1, 0, 2), V({0}));
  EXPECT_EQ(pinning_plan({0, 1}, 1, 1, 2), V({1}));
  // One rank, two threads.
  EXPECT_EQ(pinning_plan({0, 1}, 2, 0, 1), V({0, 1}));
  // Two ranks of four threads on a 16-core node, and a mask with gaps.
  EXPECT_EQ(pinning_plan({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}, 4, 1, 2), V({4, 5, 6, 7}));
  EXPECT_EQ(pinning_plan({2, 3, 6, 7}, 2, 1, 2), V({6, 7}));
  // Bound by the launcher (mpirun --bind-to core): the rank's own core, whatever its place.
  EXPECT_EQ(pinning_plan({5}, 1, 1, 2), V({5}));
  EXPECT_EQ(pinning_plan({4, 5}, 2, 1, 2), V({4, 5}));
  // More ranks than cores (--oversubscribe): ranks take the cores in turn.
  EXPECT_EQ(pinning_plan({0, 1}, 1, 2, 4), V({0}));
  EXPECT_EQ(pinning_plan({0, 1}, 1, 3, 4), V({1}));
  // Nothing known, nothing pinned.
  EXPECT_TRUE(pinning_plan({}, 2, 0, 1).empty());
}

TEST(Executor, PinnedThreadsRunEveryTaskOnTheCoreOfTheirSlot) {
  const std::vector<int> allowed = fountain::tasks::allowed_cpus();
  ASSERT_FALSE(allowed.empty());
  cpu_set_t caller_mask;
  ASSERT_EQ(sched_getaffinity(0, sizeof(caller_mask), &caller_mask), 0);
  const int threads = allowed.size() > 1 ? 2 : 1;
  // Reversed where there are two cores, so that a thread left on its first core would fail.
  std::vector<int> cpus(allowed.begin(), allowed.begin() + threads);
  std::reverse(cpus.begin(), cpus.end());

  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  TaskGraph g;
  for (int i = 0; i < 400; ++i) g.add(ty, i, -1, -1);
  g.finalize();
  // Per task: its thread's slot, the CPUs that thread may run on, and the one it ran on.
  struct Seen {
    int slot = -2;
    std::vector<int> allowed;
    int cpu = -2;
  };
  std::vector<Seen> seen(static_cast<std::size_t>(g.size()));
  // Each task waits (up to 10 s in all) until every thread has started one, so that the
  // workers' pins are checked too, not only the caller's.
  std::atomic<unsigned> slots_seen{0};
  const unsigned all_slots = (1u << threads) - 1;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  {
    Executor exec(threads, cpus);
    exec.run(g, [&](const Task& t) {
      const int slot = tbb::this_task_arena::current_thread_index();
      slots_seen.fetch_or(1u << slot);
      while (slots_seen.load() != all_slots && std::chrono::steady_clock::now() < give_up) std::this_thread::yield();
      seen[static_cast<std::size_t>(index_of(g, t))] = {slot, fountain::tasks::allowed_cpus(), sched_getcpu()};
    });
  }
  ASSERT_EQ(slots_seen.load(), all_slots) << "not every thread ran a task";
  for (int i = 0; i < g.size(); ++i) {
    const Seen& s = seen[static_cast<std::size_t>(i)];
    ASSERT_GE(s.slot, 0) << "task " << i;
    const int cpu = cpus[static_cast<std::size_t>(s.slot) % cpus.size()];
    EXPECT_EQ(s.allowed, std::vector<int>({cpu})) << "task " << i << " in slot " << s.slot;
    EXPECT_EQ(s.cpu, cpu) << "task " << i << " in slot " << s.slot;
  }
  // The caller's thread stays pinned after a run (its serial work between graphs stays put):
  // the test gives it back its mask.
  ASSERT_EQ(sched_setaffinity(0, sizeof(caller_mask), &caller_mask), 0);
}

TEST(Executor, ForEachInTaskVisitsEveryPieceOnceAndNoTaskRunsInsideAnother) {
  // One task splits its work with for_each_in_task while many small tasks are ready: every
  // piece runs once, no record lies inside another on the same thread (the waiting thread
  // is isolated to the loop's pieces), and the busy time includes the pieces.
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  TaskGraph g;
  const int big = g.add(ty, 0);
  for (int i = 1; i < 400; ++i) g.add(ty, i);
  g.finalize();
  Executor exec(2);
  auto spin = [](int n) {
    volatile double x = 1.0;
    for (int k = 0; k < n; ++k) x = x * 1.0000001 + 1e-9;
  };
  for (int repeat = 0; repeat < 10; ++repeat) {
    std::vector<std::atomic<int>> pieces(64);
    for (auto& p : pieces) p.store(0);
    std::vector<TaskRecord> rec;
    exec.run(
        g,
        [&](const Task& t) {
          if (index_of(g, t) == big) {
            exec.for_each_in_task(pieces.size(), [&](std::size_t k) {
              spin(20000);
              pieces[k].fetch_add(1);
            });
          } else {
            spin(2000);
          }
        },
        &rec);
    for (std::size_t k = 0; k < pieces.size(); ++k) ASSERT_EQ(pieces[k].load(), 1) << "piece " << k;
    const TaskRecord& b = rec[static_cast<std::size_t>(big)];
    for (int i = 0; i < g.size(); ++i) {
      if (i == big) continue;
      const TaskRecord& r = rec[static_cast<std::size_t>(i)];
      ASSERT_GE(r.thread, 0);
      if (r.thread == b.thread) {
        EXPECT_TRUE(r.end_ns <= b.start_ns || r.start_ns >= b.end_ns) << "task " << i << " ran inside the big task";
      }
    }
    EXPECT_GT(exec.last_busy_ns(), 0);
  }
}

TEST(TaskGraph, RepeatedEdgesCountOnceAndListsKeepTheirOrder) {
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  TaskGraph g;
  for (int i = 0; i < 6; ++i) g.add(ty, i, -1, -1);
  for (int after : {4, 2, 4, 5, 2, 3, 5}) g.depends(0, after);
  g.depends(1, 3);
  g.depends(1, 3);
  g.finalize();
  const auto u0 = g.unlocks(0), u1 = g.unlocks(1);
  EXPECT_EQ(std::vector<int>(u0.begin(), u0.end()), (std::vector<int>{4, 2, 5, 3}));
  EXPECT_EQ(std::vector<int>(u1.begin(), u1.end()), (std::vector<int>{3}));
  EXPECT_EQ(g.num_dependencies(), 5u);
}

TEST(Executor, RunBesideRunsBothAndReturnsAfterBoth) {
  Executor exec(2);
  for (int repeat = 0; repeat < 50; ++repeat) {
    std::vector<int> a(1000, 0), b(1000, 0);
    std::atomic<int> calls{0};
    exec.run_beside([&] { std::fill(a.begin(), a.end(), repeat); ++calls; },
                    [&] { std::fill(b.begin(), b.end(), -repeat); ++calls; });
    ASSERT_EQ(calls.load(), 2);
    EXPECT_TRUE(std::all_of(a.begin(), a.end(), [&](int v) { return v == repeat; }));
    EXPECT_TRUE(std::all_of(b.begin(), b.end(), [&](int v) { return v == -repeat; }));
  }
}

TEST(Executor, DiamondNeverStartsBeforeItsPredecessorsEnd) {
  TaskTypeRegistry types;
  const int ty = types.add({"node", "", "test"});
  TaskGraph g;
  // Many diamonds a -> {b, c} -> d side by side, each stage a little slow.
  constexpr int diamonds = 50;
  std::vector<std::pair<int, int>> edges;
  for (int k = 0; k < diamonds; ++k) {
    const int a = g.add(ty, k);
    const int b = g.add(ty, k);
    const int c = g.add(ty, k);
    const int d = g.add(ty, k);
    const std::pair<int, int> diamond[] = {{a, b}, {a, c}, {b, d}, {c, d}};
    for (auto [x, y] : diamond) {
      g.depends(x, y);
      edges.emplace_back(x, y);
    }
  }
  g.finalize();

  Executor exec(2);
  std::vector<TaskRecord> rec;
  exec.run(g, [](const Task&) { spin_for(std::chrono::microseconds(20)); }, &rec);
  ASSERT_EQ(rec.size(), static_cast<std::size_t>(g.size()));
  for (const auto& r : rec) {
    EXPECT_GE(r.thread, 0);
    EXPECT_LE(r.start_ns, r.end_ns);
  }
  for (auto [x, y] : edges)
    EXPECT_GE(rec[static_cast<std::size_t>(y)].start_ns, rec[static_cast<std::size_t>(x)].end_ns)
        << "task " << y << " started before its predecessor " << x << " ended";
}

TEST(Executor, InactiveTaskInAChainPassesTheOrderOn) {
  TaskTypeRegistry types;
  const int ty = types.add({"step", "", "test"});
  TaskGraph g;
  constexpr int chains = 8, length = 30;
  std::vector<std::vector<int>> tasks_of(chains);
  for (int i = 0; i < length; ++i)
    for (int c = 0; c < chains; ++c) tasks_of[c].push_back(g.add(ty, c, -1, /*writes=*/c));
  g.finalize();
  // Switch off a task in the middle of every chain (and two in a row in chain 0).
  for (int c = 0; c < chains; ++c) g.task(tasks_of[c][length / 2]).active = false;
  g.task(tasks_of[0][length / 2 + 1]).active = false;

  std::vector<std::vector<int>> seen(chains);  // one vector per chain: no two writers at once
  std::vector<std::atomic<bool>> inside(chains);   // relaxed overlap guard, as above
  for (auto& b : inside) b.store(false);
  std::atomic<int> overlaps{0};
  Executor exec(2);
  std::vector<TaskRecord> rec;
  exec.run(
      g,
      [&](const Task& t) {
        const auto c = static_cast<std::size_t>(t.writes);
        if (inside[c].exchange(true, std::memory_order_relaxed)) {
          overlaps.fetch_add(1, std::memory_order_relaxed);
          return;
        }
        seen[c].push_back(index_of(g, t));
        inside[c].store(false, std::memory_order_relaxed);
      },
      &rec);
  EXPECT_EQ(overlaps.load(), 0);

  for (int c = 0; c < chains; ++c) {
    std::vector<int> expected;
    for (int t : tasks_of[c])
      if (g.task(t).active) expected.push_back(t);
    EXPECT_EQ(seen[static_cast<std::size_t>(c)], expected) << "chain " << c;
    // The task after the inactive one starts after the one before it ended.
    const int before = tasks_of[c][length / 2 - 1];
    const int after = tasks_of[c][c == 0 ? length / 2 + 2 : length / 2 + 1];
    EXPECT_GE(rec[static_cast<std::size_t>(after)].start_ns, rec[static_cast<std::size_t>(before)].end_ns);
    EXPECT_EQ(rec[static_cast<std::size_t>(tasks_of[c][length / 2])].thread, -1);
  }
}

TEST(Executor, ExceptionInATaskPropagatesOutOfRun) {
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  TaskGraph g;
  for (int i = 0; i < 64; ++i) g.add(ty, i % 4, -1, i % 4);
  g.finalize();
  const int bad = 37;

  Executor exec(2);
  EXPECT_THROW(exec.run(g,
                        [&](const Task& t) {
                          if (index_of(g, t) == bad) throw std::runtime_error("task failed");
                        }),
               std::runtime_error);

  // The executor is still usable afterwards.
  std::atomic<int> ran{0};
  exec.run(g, [&](const Task&) { ++ran; });
  EXPECT_EQ(ran.load(), g.size());
}

// With a list of tasks, only those run; dependencies between listed tasks are honoured and
// unlisted ones neither run nor hold anything up.
TEST(Executor, OnlyListedTasksRunInDependencyOrder) {
  TaskTypeRegistry types;
  const int ty = types.add({"step", "", "test"});
  TaskGraph g;
  const int a = g.add(ty, 0), b = g.add(ty, 1), c = g.add(ty, 2), d = g.add(ty, 3);
  g.depends(a, b);  // a -> b -> d, and c (unlisted) -> d
  g.depends(b, d);
  g.depends(c, d);
  g.finalize();
  const std::vector<int> only{a, b, d};
  std::vector<int> order;
  std::atomic<int> running{0};
  std::atomic<int> overlaps{0};
  Executor exec(2);
  exec.run(
      g,
      [&](const Task& t) {
        if (running.fetch_add(1) != 0) overlaps.fetch_add(1);
        order.push_back(t.ci);
        running.fetch_sub(1);
      },
      nullptr, &only);
  EXPECT_EQ(overlaps.load(), 0);  // a chain of dependencies: never two at once
  EXPECT_EQ(order, (std::vector<int>{0, 1, 3}));
}

// The ancestors of a set of tasks (what the engine runs first so that sends go early): every
// listed task that leads to a target, through listed tasks only, and nothing else.
TEST(TaskGraph, AncestorsFollowListedTasksBackFromTheTargets) {
  TaskTypeRegistry types;
  const int ty = types.add({"step", "", "test"});
  TaskGraph g;
  std::vector<int> t;
  for (int k = 0; k < 8; ++k) t.push_back(g.add(ty, k));
  // 0 -> 1 -> 3 <- 2; 4 alone; 5 (unlisted) -> 6 -> 3; 7 -> 5; 3 -> ... nothing.
  g.depends(t[0], t[1]);
  g.depends(t[1], t[3]);
  g.depends(t[2], t[3]);
  g.depends(t[5], t[6]);
  g.depends(t[6], t[3]);
  g.depends(t[7], t[5]);
  EXPECT_THROW(g.ancestors(std::vector<int>{t[3]}, std::vector<char>(8, 1)), std::logic_error);
  g.finalize();
  std::vector<char> listed(8, 1);
  listed[5] = 0;
  const std::vector<char> marked = g.ancestors(std::vector<int>{t[3]}, listed);
  EXPECT_EQ(marked, (std::vector<char>{1, 1, 1, 1, 0, 0, 1, 0}));
  // With every task listed, 5 and 7 lead to 3 as well; a second call reuses the lists.
  EXPECT_EQ(g.ancestors(std::vector<int>{t[3]}, std::vector<char>(8, 1)), (std::vector<char>{1, 1, 1, 1, 0, 1, 1, 1}));
  EXPECT_EQ(g.ancestors(std::vector<int>{t[4]}, std::vector<char>(8, 1)), (std::vector<char>{0, 0, 0, 0, 1, 0, 0, 0}));
}

// Urgent tasks (those whose results other ranks wait for) run first: a lone thread runs every
// urgent task as soon as it is ready, before any other ready task, and the order never breaks
// a dependency; with two threads every task still runs once, in dependency order.
TEST(Executor, UrgentTasksRunFirstOnALoneThread) {
  TaskTypeRegistry types;
  const int ty = types.add({"step", "", "test"});
  TaskGraph g;
  std::vector<int> t;
  for (int k = 0; k < 12; ++k) t.push_back(g.add(ty, k));
  // Roots 0-7; 5 -> 8 -> 9 and 2 -> 10 -> 11; urgent: 2, 5, 8, 10.
  g.depends(t[5], t[8]);
  g.depends(t[8], t[9]);
  g.depends(t[2], t[10]);
  g.depends(t[10], t[11]);
  g.finalize();
  Executor::Gates gates;
  gates.poll = [](std::span<const int>, std::vector<int>&) {};
  gates.urgent.assign(12, 0);
  for (int u : {2, 5, 8, 10}) gates.urgent[static_cast<std::size_t>(u)] = 1;
  for (int threads : {1, 2}) {
    std::mutex m;
    std::vector<int> order;
    Executor exec(threads);
    exec.run(
        g,
        [&](const Task& task) {
          const std::lock_guard<std::mutex> lock(m);
          order.push_back(task.ci);
        },
        nullptr, nullptr, &gates);
    ASSERT_EQ(order.size(), 12u) << threads << " threads";
    std::vector<int> place(12, -1);
    for (std::size_t k = 0; k < order.size(); ++k) place[static_cast<std::size_t>(order[k])] = static_cast<int>(k);
    for (int k = 0; k < 12; ++k) EXPECT_GE(place[static_cast<std::size_t>(k)], 0) << "task " << k << " never ran";
    for (auto [a, b] : std::vector<std::pair<int, int>>{{5, 8}, {8, 9}, {2, 10}, {10, 11}})
      EXPECT_LT(place[static_cast<std::size_t>(a)], place[static_cast<std::size_t>(b)]) << threads << " threads";
    if (threads == 1) {
      std::vector<int> first(order.begin(), order.begin() + 4);
      std::sort(first.begin(), first.end());
      EXPECT_EQ(first, (std::vector<int>{2, 5, 8, 10})) << "run order: " << ::testing::PrintToString(order);
    }
  }
}

// Gates (messages from other ranks): a gated task runs once its gate is named by the poll
// and its predecessors are done, never earlier, with no more than `threads` tasks running at
// once (the threads that poll are the ones that compute). Half the gates are opened by tasks of the
// same graph (a rank's own sends, as when two ranks exchange), half from another thread.
TEST(Executor, GatedTasksWaitForTheirGateAndNoThreadBlocks) {
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  for (int threads : {1, 2}) {
    TaskGraph g;
    constexpr int pairs = 40;
    std::vector<int> opener(pairs), gated(pairs), after(pairs);
    for (int k = 0; k < pairs; ++k) {
      opener[static_cast<std::size_t>(k)] = g.add(ty, k);
      gated[static_cast<std::size_t>(k)] = g.add(ty, k);
      after[static_cast<std::size_t>(k)] = g.add(ty, k);
      g.depends(gated[static_cast<std::size_t>(k)], after[static_cast<std::size_t>(k)]);
    }
    g.finalize();
    std::vector<std::atomic<int>> open(pairs);
    for (auto& o : open) o.store(0);
    std::atomic<int> running{0}, most{0};
    std::vector<std::atomic<int>> runs(static_cast<std::size_t>(g.size()));
    for (auto& r : runs) r.store(0);
    std::vector<std::atomic<int>> gate_seen_open(static_cast<std::size_t>(g.size()));
    for (auto& r : gate_seen_open) r.store(0);

    Executor::Gates gates;
    gates.tasks = gated;
    gates.poll = [&](std::span<const int> waiting, std::vector<int>& opened) {
      for (int t : waiting)
        if (open[static_cast<std::size_t>(g.task(t).ci)].load()) opened.push_back(t);
    };
    // The odd gates open from outside, a little later.
    std::thread remote([&] {
      for (int k = 1; k < pairs; k += 2) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));
        open[static_cast<std::size_t>(k)].store(1);
      }
    });
    Executor exec(threads);
    exec.run(
        g,
        [&](const Task& t) {
          const int now = running.fetch_add(1) + 1;
          int m = most.load();
          while (now > m && !most.compare_exchange_weak(m, now)) {
          }
          const int i = index_of(g, t);
          runs[static_cast<std::size_t>(i)].fetch_add(1);
          if (i == gated[static_cast<std::size_t>(t.ci)]) gate_seen_open[static_cast<std::size_t>(i)] = open[static_cast<std::size_t>(t.ci)].load();
          if (i == opener[static_cast<std::size_t>(t.ci)] && t.ci % 2 == 0) open[static_cast<std::size_t>(t.ci)].store(1);
          spin_for(std::chrono::microseconds(10));
          running.fetch_sub(1);
        },
        nullptr, nullptr, &gates);
    remote.join();
    for (int i = 0; i < g.size(); ++i) EXPECT_EQ(runs[static_cast<std::size_t>(i)].load(), 1) << "task " << i;
    for (int t : gated) EXPECT_EQ(gate_seen_open[static_cast<std::size_t>(t)].load(), 1) << "gated task " << t << " ran before its gate opened";
    EXPECT_LE(most.load(), threads) << "more tasks ran at once than threads";
  }
}

// The polling done by idle threads: every task of the graph is gated (nothing can start
// before a poll), gates open from another thread in the reverse of the dependency order (a
// gate opened while its task still waits for a gated predecessor must not end the polling),
// and the poll is never entered by two threads at once.
TEST(Executor, AllTasksGatedAndChainedStillRunAndPollsNeverOverlap) {
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  for (int threads : {1, 2, 3}) {
    TaskGraph g;
    constexpr int chain = 12;
    std::vector<int> tasks;
    for (int k = 0; k < chain; ++k) {
      tasks.push_back(g.add(ty, k));
      if (k > 0) g.depends(tasks[static_cast<std::size_t>(k - 1)], tasks.back());
    }
    g.finalize();
    std::vector<std::atomic<int>> open(chain);
    for (auto& o : open) o.store(0);
    std::atomic<int> in_poll{0}, overlaps{0}, polls{0};
    Executor::Gates gates;
    gates.tasks = tasks;
    gates.poll = [&](std::span<const int> waiting, std::vector<int>& opened) {
      if (in_poll.fetch_add(1) != 0) overlaps.fetch_add(1);
      polls.fetch_add(1);
      for (int t : waiting)
        if (open[static_cast<std::size_t>(g.task(t).ci)].load()) opened.push_back(t);
      in_poll.fetch_sub(1);
    };
    std::thread remote([&] {
      for (int k = chain - 1; k >= 0; --k) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        open[static_cast<std::size_t>(k)].store(1);
      }
    });
    std::vector<int> order;
    std::mutex order_mutex;
    Executor exec(threads);
    exec.run(
        g,
        [&](const Task& t) {
          EXPECT_EQ(open[static_cast<std::size_t>(t.ci)].load(), 1) << "task " << t.ci << " ran before its gate opened";
          const std::lock_guard lock(order_mutex);
          order.push_back(t.ci);
        },
        nullptr, nullptr, &gates);
    remote.join();
    std::vector<int> expected(chain);
    for (int k = 0; k < chain; ++k) expected[static_cast<std::size_t>(k)] = k;
    EXPECT_EQ(order, expected) << threads << " threads";
    EXPECT_EQ(overlaps.load(), 0) << "two threads polled at once";
    EXPECT_GT(polls.load(), 0);
  }
}

// A failed task ends the run even while gates wait for messages that will never come (the
// other ranks are about to be stopped): the idle threads stop polling and the error comes out.
TEST(Executor, FailureWhileGatesWaitEndsTheRun) {
  TaskTypeRegistry types;
  const int ty = types.add({"t", "", "test"});
  for (int threads : {1, 2}) {
    TaskGraph g;
    const int bad = g.add(ty, 0);
    const int gated = g.add(ty, 1);
    const int after = g.add(ty, 2);
    g.depends(gated, after);
    g.finalize();
    Executor::Gates gates;
    gates.tasks = {gated};
    gates.poll = [](std::span<const int>, std::vector<int>&) {};  // never opens
    Executor exec(threads);
    std::atomic<int> ran_after{0};
    EXPECT_THROW(exec.run(
                     g,
                     [&](const Task& t) {
                       if (index_of(g, t) == bad) throw std::runtime_error("task failed");
                       if (index_of(g, t) == after) ran_after.fetch_add(1);
                     },
                     nullptr, nullptr, &gates),
                 std::runtime_error)
        << threads << " threads";
    EXPECT_EQ(ran_after.load(), 0);
  }
}
