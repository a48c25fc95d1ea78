// The JSON fields every whole-run benchmark reports about ranks: layout, traffic per step, and where the wall time went.
#pragma once
#include <fmt/format.h>

#include <sys/resource.h>

#include <string>

#include "engine/Engine.hpp"

namespace fountain::bench {

// What the engine had counted when the timed part of a run began.
struct RankCounters {
  double bytes = 0, messages = 0, graph_s = 0, exchange_s = 0, ghost_bytes = 0, recut_bytes = 0, rebuild_s = 0;
  double cpu_s = 0;  // user + system time of the whole process, every thread
  int rebuilds = 0;
  Engine::TreeAssembly tree;  // domain.assemble_gravity_tree: the trees assembled, and what was received for them
  static RankCounters of(const Engine& e) {
    return {static_cast<double>(e.bytes_sent()), static_cast<double>(e.messages_sent()), e.graph_seconds(),
            e.exchange_seconds(), static_cast<double>(e.ghost_bytes_sent()),
            static_cast<double>(e.recut_bytes_sent()), e.rebuild_seconds(), process_cpu_seconds(), e.space().rebuild_count(),
            e.tree_assembly()};
  }
  static double process_cpu_seconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
    return s(u.ru_utime) + s(u.ru_stime);
  }
};

// Rank 0's view (ranks are alike: each owns a share of the leaves).
// `busy_s` is the time inside tasks summed over threads; the waiting share is the thread
// time not spent in tasks while the graph ran, plus the exchanges after it, over the wall.
inline std::string rank_fields(const Engine& e, const RankCounters& before, long long steps, double wall_s,
                               double busy_s) {
  const RankCounters now = RankCounters::of(e);
  const double per_step = steps > 0 ? 1.0 / static_cast<double>(steps) : 0.0;
  const double graph = now.graph_s - before.graph_s, exchange = now.exchange_s - before.exchange_s;
  const double thread_time = wall_s * e.threads();
  // Each rank's own: a rank that waits for another shows it in its exchanges or graph gaps.
  auto by_rank = [&](double mine) {
    std::string s = "[";
    for (double v : e.from_every_rank(mine)) s += fmt::format("{}{:.3f}", s.size() > 1 ? ", " : "", v);
    return s + "]";
  };
  const std::string graph_by_rank = by_rank(graph), exchange_by_rank = by_rank(exchange),
                    busy_by_rank = by_rank(busy_s), rebuild_by_rank = by_rank(now.rebuild_s - before.rebuild_s);
  const double assemblies = static_cast<double>(now.tree.assemblies - before.tree.assemblies);
  const double waiting = thread_time > 0 ? ((graph * e.threads() - busy_s) + exchange * e.threads()) / thread_time : 0.0;
  return fmt::format(
      "\"ranks\": {}, \"ranks_x_threads\": \"{}x{}\", \"step_ms\": {:.4f}, \"bytes_sent_per_step_rank0\": {:.0f}, "
      "\"ghost_bytes_sent_per_step_rank0\": {:.0f}, \"recut_bytes_sent_per_step_rank0\": {:.0f}, \"messages_sent_per_step_rank0\": {:.1f}, \"graph_s_rank0\": {:.3f}, \"exchange_s_rank0\": {:.3f}, "
      "\"waiting_share_rank0\": {:.4f}, \"owner_cuts\": {}, \"halo_mode\": {}, \"held_share_rank0\": {:.4f}, "
      "\"rebuilds\": {}, \"rebuild_s_rank0\": {:.3f}, \"cpu_s_rank0\": {:.3f}, \"graph_s_by_rank\": {}, \"task_busy_s_by_rank\": {}, "
      "\"exchange_s_by_rank\": {}, \"rebuild_s_by_rank\": {}, \"tree_assemblies\": {}, "
      "\"tree_nodes_received_per_assembly_rank0\": {:.1f}, \"tree_sources_received_per_assembly_rank0\": {:.1f}",
      e.ranks(), e.ranks(), e.threads(), 1e3 * wall_s * per_step, (now.bytes - before.bytes) * per_step,
      (now.ghost_bytes - before.ghost_bytes) * per_step, (now.recut_bytes - before.recut_bytes) * per_step,
      (now.messages - before.messages) * per_step, graph, exchange, waiting, e.partitions(),
      e.halo_mode() ? "true" : "false", e.held_share(), now.rebuilds - before.rebuilds, now.rebuild_s - before.rebuild_s, now.cpu_s - before.cpu_s,
      graph_by_rank, busy_by_rank, exchange_by_rank, rebuild_by_rank, assemblies,
      assemblies > 0 ? static_cast<double>(now.tree.nodes_received - before.tree.nodes_received) / assemblies : 0.0,
      assemblies > 0 ? static_cast<double>(now.tree.sources_received - before.tree.sources_received) / assemblies : 0.0);
}

}  // namespace fountain::bench
