#include "app/Simulation.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <string>
#include <vector>

#include <pthread.h>
#include <signal.h>

#include "app/OutputSchedule.hpp"
#include "app/RestartPolicy.hpp"
#include "app/RunSetup.hpp"
#include "engine/Engine.hpp"
#include "params/ParameterFile.hpp"
#include "tasks/TaskGraphDump.hpp"


#ifndef FOUNTAIN_GIT_REVISION
#define FOUNTAIN_GIT_REVISION "unknown"
#endif
#ifndef FOUNTAIN_BUILD_OPTIONS
#define FOUNTAIN_BUILD_OPTIONS "unknown"
#endif

namespace fountain {

std::string git_revision() { return FOUNTAIN_GIT_REVISION; }
std::string build_options() { return FOUNTAIN_BUILD_OPTIONS; }

namespace {

volatile std::sig_atomic_t g_terminate = 0;
extern "C" void on_sigterm(int) { g_terminate = 1; }

// A launcher may hand us SIGTERM blocked (and even already pending): unblocking it once the
// handler is in place means a stop request is never lost, however early it came.
void catch_sigterm() {
  struct sigaction action {};
  action.sa_handler = on_sigterm;
  sigemptyset(&action.sa_mask);
  sigaction(SIGTERM, &action, nullptr);
  sigset_t term;
  sigemptyset(&term);
  sigaddset(&term, SIGTERM);
  pthread_sigmask(SIG_UNBLOCK, &term, nullptr);
}

}  // namespace

std::string restart_path(const ParameterFile& params) { return params.text("output.directory") + "/restart.hdf5"; }

RunSummary run_simulation(const ParameterFile& params, const RunOptions& options) {
  const auto t_start = std::chrono::steady_clock::now();
  RunStart start = prepare_run(params, options);
  const RunConfig& config = start.config;
  Engine engine(config, std::move(start.ic.gas), std::move(start.ic.dm), std::move(start.share));
  // Rank 0 alone writes files and reports.
  const bool io_rank = engine.rank() == 0;
  const bool quiet = options.quiet || !io_rank;
  const std::string rank_suffix = engine.ranks() > 1 ? fmt::format("_rank{}", engine.rank()) : "";
  const bool dump_timeline = config.output.dump_timeline_every > 0;
  engine.set_record_timeline(dump_timeline || config.output.dump_task_graph);
  start_engine(engine, start, params, options, quiet);
  catch_sigterm();

  const TemperatureOf temperature =
      engine.cooling() ? TemperatureOf([c = engine.cooling()](double u) { return c->temperature(u); })
                       : ideal_gas_temperature(config.units, config.hydro.gamma);
  const bool restart = options.restart;
  SnapshotSeries snapshots(config, engine, temperature, restart ? start.restart.snapshots_written : 0, quiet);
  if (config.output.dump_task_graph) {
    // One file per rank: each rank's graph holds its own sends and receives.
    tasks::write_dot(engine.graph(), engine.task_types(),
                     config.output.directory + "/task_graph" + rank_suffix + ".dot");
    tasks::write_dependency_csv(engine.graph(), engine.task_types(),
                                fmt::format("{}/dependency_graph_{}.csv", config.output.directory, engine.rank()));
  }
  if (!restart) snapshots.write();
  OutputSchedule outputs(config, engine, restart ? start.restart.next_output : 1);
  RestartPolicy restarts(params, config, engine, outputs, snapshots, restart ? start.restart.serial : 0, quiet);
  StatisticsSeries statistics(config, engine, temperature, restart);
  if (statistics.enabled() && !restart) statistics.write();
  // The first restart file comes at the start, right after the first cut of the cells: a run
  // killed before its first due restart file can still be continued with --restart.
  if (!restart && restarts.enabled()) restarts.save();

  // Across ranks, the exchanges after the graph join the timeline as a row of its own.
  auto exchange_interval = [&]() -> std::vector<tasks::TimelineInterval> {
    if (engine.ranks() == 1) return {};
    const auto [begin, end] = engine.last_exchange_ns();
    return {{"exchange", "after_graph", "mpi", begin, end}};
  };
  RunSummary summary;
  while (!engine.finished()) {
    if (config.max_steps > 0 && engine.steps() >= config.max_steps) break;
    const StepInfo s = engine.step(outputs.next_ticks());
    if (!quiet && config.comoving.enabled) {
      // The clock reads ln a: the step's length is in ln a.
      fmt::print(stderr, "step {:6d}  a = {:<12.6g} z = {:<10.5g} dln_a = {:<11.4g} active = {:<8d} {}wall = {:.3f} ms\n",
                 s.step, std::exp(s.time), 1.0 / std::exp(s.time) - 1.0, s.dt, s.active, s.rebuilt ? "rebuilt " : "",
                 1e3 * s.wall_s);
    } else if (!quiet) {
      fmt::print(stderr, "step {:6d}  t = {:<12.6g} dt = {:<11.4g} active = {:<8d} {}wall = {:.3f} ms\n", s.step,
                 s.time, s.dt, s.active, s.rebuilt ? "rebuilt " : "", 1e3 * s.wall_s);
    }
    if (dump_timeline && s.active > 0 && s.step % config.output.dump_timeline_every == 0)
      tasks::write_timeline_csv(engine.records_graph(), engine.task_types(), engine.last_records(),
                                engine.rank(), s.step,
                                fmt::format("{}/timeline_step{:06d}{}.csv", config.output.directory, s.step, rank_suffix),
                                exchange_interval());
    if (statistics.due()) statistics.write();
    if (outputs.due()) {
      snapshots.write();
      outputs.advance();
    }
    if (engine.finished()) break;
    // Signals differ between ranks: they decide together.
    const bool terminate = engine.any_rank(g_terminate != 0);
    restarts.after_step(s, terminate);
    if (terminate) {
      if (io_rank)
        fmt::print(stderr, "stopped by SIGTERM at step {}; continue with: fountain run {} --restart\n", engine.steps(),
                   params.origin());
      summary.terminated = true;
      break;
    }
    if (options.abandon_after_steps > 0 && engine.steps() >= options.abandon_after_steps) {
      if (io_rank) fmt::print(stderr, "abandoned after step {}, as asked: nothing more written\n", engine.steps());
      summary.abandoned = true;
      break;
    }
  }
  restarts.stop();
  if (!summary.terminated && !summary.abandoned) snapshots.write();
  summary.snapshots = snapshots.written();
  summary.steps = engine.steps();
  summary.comoving = config.comoving.enabled;
  summary.final_time = summary.comoving ? std::exp(engine.time()) : engine.time();
  summary.ranks = engine.ranks();
  summary.partitions = engine.partitions();
  summary.bytes_sent = engine.bytes_sent();
  summary.messages_sent = engine.messages_sent();
  summary.graph_s = engine.graph_seconds();
  summary.exchange_s = engine.exchange_seconds();
  summary.halo_mode = engine.halo_mode();
  summary.held_share = engine.held_share();
  const Engine::MeshShare mesh = engine.mesh_share();
  summary.mesh_cells = mesh.cells;
  summary.mesh_planes = mesh.planes;
  summary.mesh_bytes = mesh.bytes;
  summary.tree_assembly = engine.tree_assembly();
  summary.event_rounds = engine.event_rounds();
  summary.h_max_capped = engine.h_max_capped();
  summary.h_min_held = engine.h_min_held();
  summary.msph_decoupled = engine.msph_decoupled();
  summary.star_formation = engine.star_formation_total();
  for (std::size_t i = 0; i < engine.gas().size(); ++i) summary.reservoir_held += engine.gas().reservoir[i];
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return summary;
}

}  // namespace fountain
