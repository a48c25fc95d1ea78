#include "app/Simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string_view>
#include <tuple>
#include <vector>

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include "core/Error.hpp"
#include "app/OutputFolder.hpp"
#include "core/PeriodicWrap.hpp"
#include "engine/Engine.hpp"
#include "io/InitialConditions.hpp"
#include "io/RestartFile.hpp"
#include "io/StatisticsFile.hpp"
#include "io/Snapshot.hpp"
#include "params/ParameterFile.hpp"
#include "tasks/TaskGraphDump.hpp"

#ifndef FOUNTAIN_GIT_REVISION
#define FOUNTAIN_GIT_REVISION "unknown"
#endif
#ifndef FOUNTAIN_BUILD_OPTIONS
#define FOUNTAIN_BUILD_OPTIONS "unknown"
#endif

namespace fountain {

namespace fs = std::filesystem;

std::string git_revision() { return FOUNTAIN_GIT_REVISION; }
std::string build_options() { return FOUNTAIN_BUILD_OPTIONS; }

namespace {

// Fails early, before any work, if the output folder cannot be created or written.
void check_output_directory(const ParameterFile& params, const std::string& dir) {
  if (dir.empty()) throw InputError(fmt::format("{} is empty: name the output folder", params.where("output.directory")));
  if (params.text("output.basename").empty())
    throw InputError(fmt::format("{} is empty: snapshots need a name", params.where("output.basename")));
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(fmt::format("output directory '{}' cannot be created: {}", dir,
                                 ec ? ec.message() : "a file of that name exists"));
  // Named by process, so ranks probing one folder at once do not remove each other's probe.
  const fs::path probe = fs::path(dir) / fmt::format(".fountain_write_test_{}", static_cast<long>(::getpid()));
  {
    std::ofstream out(probe);
    if (!(out << "ok") || !out.flush())
      throw InputError(fmt::format("output directory '{}' is not writable", dir));
  }
  fs::remove(probe, ec);
}

std::string resolve_ic_path(const ParameterFile& params) {
  if (params.text("initial_conditions.file").empty())
    throw InputError(fmt::format("{} is empty: name the initial conditions file",
                                 params.where("initial_conditions.file")));
  fs::path ic = params.text("initial_conditions.file");
  if (ic.is_relative()) ic = fs::path(params.origin()).parent_path() / ic;
  return ic.lexically_normal().string();
}

// Gas particles at one position have no defined density: the smoothing length cannot
// converge. Checked before the run, where the cause can still be named (in a periodic box,
// positions are compared once folded into it: a BoxSize smaller than the particles' extent
// folds them onto each other).
void check_distinct_positions(const io::InitialConditions& ic, bool periodic, const std::string& path) {
  const std::size_t n = ic.gas.size();
  std::vector<Vec3> x(ic.gas.x);
  if (periodic)
    for (Vec3& p : x) p = wrap_into_box(p, ic.box_size);
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  auto less = [&](std::size_t a, std::size_t b) {
    return std::tie(x[a].x, x[a].y, x[a].z) < std::tie(x[b].x, x[b].y, x[b].z);
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < n; ++k) {
    const std::size_t a = order[k - 1], b = order[k];
    if (x[a] != x[b]) continue;
    std::size_t same = 2;
    while (k + 1 < n && x[order[k + 1]] == x[a]) ++k, ++same;
    throw InputError(fmt::format(
        "{}: gas particles ID {} and ID {}{} lie at the same position ({}, {}, {}){}, where SPH cannot give them a "
        "density{}",
        path, ic.gas.id[a], ic.gas.id[b], same > 2 ? fmt::format(" (and {} more)", same - 2) : "", x[a].x, x[a].y,
        x[a].z, periodic ? " once folded into the periodic box" : "",
        periodic ? fmt::format(" (is /Header/BoxSize = ({}, {}, {}) smaller than the particles' extent?)", ic.box_size.x,
                               ic.box_size.y, ic.box_size.z)
                 : ""));
  }
}

// A periodic run's particles must fit its box: ones that span more than the box (beyond the
// drift of a snapshot's last steps) mean BoxSize is not the box they were laid in.
void check_fits_periodic_box(const io::InitialConditions& ic, const std::string& path) {
  if (!(ic.box_size.x > 0 && ic.box_size.y > 0 && ic.box_size.z > 0))
    throw InputError(fmt::format("{}: periodic run needs a positive /Header/BoxSize", path));
  constexpr double kSlack = 1.1;
  for (int k = 0; k < 3; ++k) {
    double lo = 1e300, hi = -1e300;
    for (const auto* xs : {&ic.gas.x, &ic.dm.x})
      for (const Vec3& p : *xs) lo = std::min(lo, p[k]), hi = std::max(hi, p[k]);
    if (hi - lo > kSlack * ic.box_size[k])
      throw InputError(fmt::format("{}: the particles span {} along {} (from {} to {}), more than the periodic box's "
                                   "side /Header/BoxSize = {}: is BoxSize in the particles' units?",
                                   path, hi - lo, "xyz"[k], lo, hi, ic.box_size[k]));
  }
  for (const auto* xs : {&ic.gas.x, &ic.dm.x})
    for (std::size_t i = 0; i < xs->size(); ++i)
      for (int k = 0; k < 3; ++k)
        if ((*xs)[i][k] < -ic.box_size[k] || (*xs)[i][k] > 2 * ic.box_size[k])
          throw InputError(fmt::format("{}: {} particle ID {} lies far outside the periodic box", path,
                                       xs == &ic.gas.x ? "gas" : "dark matter",
                                       xs == &ic.gas.x ? ic.gas.id[i] : ic.dm.id[i]));
}

}  // namespace

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

// A restart must continue the same problem: every parameter must match but the threads
// and their pinning, the output directory (a run folder may be moved or copied and
// continued) and the task-graph and timeline dumps (diagnostics: a slow run may be resumed
// to look at it).
void check_same_parameters(const io::RestartState& state, const ParameterFile& params, const std::string& path) {
  const ParameterFile saved = ParameterFile::parse(state.parameters_yaml, path + ":/Restart/Parameters");
  constexpr std::array<std::string_view, 5> may_change = {"run.threads", "run.pin_threads", "output.directory",
                                                          "output.dump_task_graph", "output.dump_timeline_every"};
  for (const auto& [key, value] : params.values()) {
    if (std::find(may_change.begin(), may_change.end(), key) != may_change.end()) continue;
    const auto it = saved.values().find(key);
    if (it == saved.values().end() || it->second != value)
      throw InputError(fmt::format("{}: restart file was written with {} = {}, but {} says {}", path, key,
                                   it == saved.values().end() ? "(unset)" : it->second, params.origin(), value));
  }
}

}  // namespace

std::string restart_path(const ParameterFile& params) { return params.text("output.directory") + "/restart.hdf5"; }

RunSummary run_simulation(const ParameterFile& params, const RunOptions& options) {
  bool quiet = options.quiet;
  const bool restart = options.restart;
  const long long abandon_after_steps = options.abandon_after_steps;
  const auto t_start = std::chrono::steady_clock::now();
  RunConfig config = RunConfig::from(params);
  if (options.threads)
    config.threads = static_cast<int>(
        std::stoll(ParameterFile::check("run.threads", std::to_string(*options.threads), "option -t,--threads")));
  const std::string ic_path = resolve_ic_path(params);
  check_output_directory(params, config.output.directory);
  // Rank 0 holds the folder for the whole run; it alone writes snapshots and the master files.
  std::unique_ptr<OutputFolderLock> lock;
  if (options.rank == 0) {
    lock = std::make_unique<OutputFolderLock>(config.output.directory);
    if (!lock->unsupported().empty()) fmt::print(stderr, "warning: {}\n", lock->unsupported());
    if (!lock->stale_holder().empty())
      fmt::print(stderr, "note: took over the lock of {} left by a run that did not end ({})\n",
                 config.output.directory, lock->stale_holder());
    guard_output_folder(config.output.directory, config.output.basename, {ic_path, params.origin()}, restart,
                        options.overwrite);
  }
  io::InitialConditions ic = io::read_initial_conditions(ic_path);
  // A snapshot used as initial conditions carries its time: the run goes on from there.
  if (!params.was_given("run.t_begin")) {
    config.t_begin = ic.time;
    config.check_times(params, fmt::format("/Header/Time of {}", ic_path));
  } else if (ic.time != config.t_begin && options.rank == 0) {
    fmt::print(stderr, "warning: {} = {} differs from /Header/Time = {} of {}; the run starts at {}\n",
               params.where("run.t_begin"), config.t_begin, ic.time, ic_path, config.t_begin);
  }
  if (config.space.periodic) check_fits_periodic_box(ic, ic_path);
  check_distinct_positions(ic, config.space.periodic, ic_path);
  io::RestartState state;
  if (restart) {
    state = io::read_restart(restart_path(params));
    check_same_parameters(state, params, restart_path(params));
    if (state.dm.count(Species::DarkMatter) != ic.dm.size())
      throw InputError(fmt::format("{}: restart file holds {} dark matter particles, but the initial conditions {} "
                                   "have {}",
                                   restart_path(params), state.dm.count(Species::DarkMatter), resolve_ic_path(params),
                                   ic.dm.size()));
    ic.gas = std::move(state.gas);
    ic.dm = std::move(state.dm);
  }
  config.space.box_size = ic.box_size;

  Engine engine(config, std::move(ic.gas), std::move(ic.dm));
  // Every rank holds the whole state; rank 0 alone writes files and reports.
  const bool io_rank = engine.rank() == 0;
  if (!io_rank) quiet = true;
  const std::string rank_suffix = engine.ranks() > 1 ? fmt::format("_rank{}", engine.rank()) : "";
  const bool dump_timeline = config.output.dump_timeline_every > 0;
  engine.set_record_timeline(dump_timeline || config.output.dump_task_graph);
  if (restart) {
    engine.restore(state.ti_current, state.steps, state.ti_step_begin);
    engine.set_radiated_energy(state.radiated_energy);
    engine.set_star_formation_total(state.star_formation);
    if (state.next_particle_id > 0) engine.set_next_particle_id(state.next_particle_id);
    // A file written inside a step holds its end; the run goes on from the step's start.
    if (!quiet)
      fmt::print(stderr, "restarted from {} at t = {:.6g}, step {}\n", restart_path(params),
                 engine.timeline().time(state.ti_step_begin), engine.steps());
  } else {
    engine.initialise();
  }
  catch_sigterm();

  io::SnapshotInfo info;
  info.box_size = config.space.box_size;
  info.periodic = config.space.periodic;
  info.units = config.units;
  info.gamma = config.hydro.gamma;
  info.parameters_yaml = config.parameters_yaml;
  info.git_revision = git_revision();
  info.build_options = build_options();

  const TemperatureOf temperature =
      engine.cooling() ? TemperatureOf([c = engine.cooling()](double u) { return c->temperature(u); })
                       : ideal_gas_temperature(config.units, config.hydro.gamma);
  info.temperature = temperature;
  info.star_formation = config.star_formation.enabled;

  // Across ranks, the exchanges after the graph join the timeline as a row of its own.
  auto exchange_interval = [&]() -> std::vector<tasks::TimelineInterval> {
    if (engine.ranks() == 1) return {};
    const auto [start, end] = engine.last_exchange_ns();
    return {{"exchange", "after_graph", "mpi", start, end}};
  };
  RunSummary summary;
  auto write = [&] {
    engine.drift_all();
    info.time = engine.time();
    info.step = engine.steps();
    const std::string path = fmt::format("{}/{}_{:04d}.hdf5", config.output.directory, config.output.basename,
                                         summary.snapshots);
    if (io_rank) io::write_snapshot(path, engine.gas(), engine.dark_matter(), info);
    if (!quiet) fmt::print(stderr, "snapshot {} at t = {:.6g}\n", path, info.time);
    ++summary.snapshots;
  };
  summary.snapshots = restart ? state.snapshots_written : 0;
  if (config.output.dump_task_graph) {
    // One file per rank: each rank's graph holds its own sends and receives.
    tasks::write_dot(engine.graph(), engine.task_types(),
                     config.output.directory + "/task_graph" + rank_suffix + ".dot");
    tasks::write_dependency_csv(engine.graph(), engine.task_types(),
                                fmt::format("{}/dependency_graph_{}.csv", config.output.directory, engine.rank()));
  }
  if (!restart) write();

  const double dt_out = config.output.delta_time;
  int next_output = restart ? state.next_output : 1;
  auto last_restart = std::chrono::steady_clock::now();
  bool restart_wanted = false;  // due, waiting for a recut (below)
  // Writes the state as it stands: right after a recut of the cells (restore() recuts the
  // same particles into the same cells).
  long long restart_serial = restart ? state.serial : 0;
  auto save_restart = [&] {
    io::RestartState out;
    const std::string path = restart_path(params);
    if (engine.ranks() == 1) {
      out.gas = engine.gas();
      out.dm = engine.dark_matter();
    }
    out.ti_current = engine.ti_current();
    out.ti_step_begin = engine.ti_step_begin();
    out.steps = engine.steps();
    out.snapshots_written = summary.snapshots;
    out.next_output = next_output;
    out.radiated_energy = engine.radiated_energy();
    out.next_particle_id = engine.next_particle_id();
    out.star_formation = engine.star_formation_total();
    out.parameters_yaml = config.parameters_yaml;
    if (engine.ranks() == 1) {
      io::write_restart(path, out);
      io::remove_stale_restart_pieces(path);  // of a set an earlier run on several ranks wrote
    } else {
      // Each rank writes the particles of its own cells (current on it in halo mode too),
      // then rank 0 the master naming the pieces; the previous set stays whole until then.
      ++restart_serial;
      const auto [gas_owned, dm_owned] = engine.owned_particles();
      io::RestartPiece piece;
      piece.gas = engine.gas();
      piece.gas.permute(gas_owned);
      piece.dm = engine.dark_matter();
      piece.dm.permute(dm_owned);
      piece.gas_index.assign(gas_owned.begin(), gas_owned.end());
      piece.dm_index.assign(dm_owned.begin(), dm_owned.end());
      const std::filesystem::path dir = std::filesystem::path(path).parent_path();
      io::write_restart_piece((dir / io::restart_piece_name(path, restart_serial, engine.rank())).string(), piece);
      (void)engine.any_rank(false);  // every piece is in place before the master names it
      if (io_rank) {
        io::write_restart_master(path, out, restart_serial, engine.ranks(), engine.gas().size(),
                                 engine.dark_matter().size());
        io::remove_stale_restart_pieces(path);
      }
    }
    last_restart = std::chrono::steady_clock::now();
    restart_wanted = false;
    if (!quiet) fmt::print(stderr, "restart file {} at step {}\n", restart_path(params), engine.steps());
  };
  // A restart file that is due (by steps or minutes) is written at the next recut the run
  // makes anyway: inside a step, before its tasks (Engine::set_after_rebuild), or after a
  // step that ended with one, once the step's outputs are written; so when it is written
  // (which depends on the wall clock) changes nothing in the run. Only on SIGTERM, or if no
  // recut comes within kMostStepsWaiting steps, are the cells recut for it: that recut then
  // starts a path of its own (the restarted run follows it, bit for bit).
  constexpr long long kMostStepsWaiting = 1000;
  long long wanted_since = 0;
  auto write_restart_now = [&] {
    engine.rebuild_now();
    save_restart();
  };
  engine.set_after_rebuild([&] {
    if (restart_wanted) save_restart();
  });
  auto next_output_ticks = [&] {
    if (dt_out <= 0.0) return TimeLine::ticks;
    const double t = config.t_begin + next_output * dt_out;
    return t >= config.t_end ? TimeLine::ticks : engine.to_ticks(t);
  };
  IntegerTime ti_out = next_output_ticks();
  // Never a step of length zero, never two snapshots at one time: an output time at or
  // before the end of the last step done is passed over. (A restart from inside a step stands
  // at that step's end but redoes it: an output at its end is still to be written.)
  auto skip_past_outputs = [&] {
    while (ti_out <= engine.ti_step_begin() && ti_out < TimeLine::ticks) {
      ++next_output;
      ti_out = next_output_ticks();
    }
  };
  skip_past_outputs();

  std::unique_ptr<io::StatisticsFile> statistics;
  if (config.output.statistics_every > 0 && io_rank)
    statistics = std::make_unique<io::StatisticsFile>(config.output.directory + "/statistics.txt", restart);
  const analysis::FigurePhases phases = analysis::FigurePhases::paper(config.units);
  // The star formation rate of a line is the mean since the previous line.
  double sf_mass_before = engine.star_formation_total().mass_formed, sf_time_before = engine.time();
  const double msun_per_mass = config.units.mass_cgs / 1.988409870698051e33;
  const double years_per_time = config.units.time_cgs() / 3.15576e7;
  auto write_statistics = [&] {
    analysis::Diagnostics d = analysis::measure(engine.gas(), engine.dark_matter(), temperature, phases);
    d.radiated = engine.radiated_energy();
    const auto& sf = engine.star_formation_total();
    const double elapsed = engine.time() - sf_time_before;
    if (elapsed > 0.0)
      d.sfr_msun_per_yr = (sf.mass_formed - sf_mass_before) * msun_per_mass / (elapsed * years_per_time);
    sf_mass_before = sf.mass_formed;
    sf_time_before = engine.time();
    d.feedback_own = sf.energy_own;
    d.feedback_reservoir = sf.energy_reservoir;
    d.feedback_hot = sf.energy_hot;
    d.thermal_locked = sf.thermal_locked;
    statistics->write(engine.time(), engine.steps(), d);
  };
  if (config.output.statistics_every > 0 && !restart) {
    engine.gather_state();
    if (statistics) write_statistics();
  }
  // The first restart file comes at the start, right after the first cut of the cells: a run
  // killed before its first due restart file can still be continued with --restart.
  if (!restart && (config.restart.every_steps > 0 || config.restart.every_minutes > 0)) save_restart();

  while (!engine.finished()) {
    if (config.max_steps > 0 && engine.steps() >= config.max_steps) break;
    const StepInfo s = engine.step(ti_out);
    if (!quiet)
      fmt::print(stderr, "step {:6d}  t = {:<12.6g} dt = {:<11.4g} active = {:<8d} {}wall = {:.3f} ms\n", s.step,
                 s.time, s.dt, s.active, s.rebuilt ? "rebuilt " : "", 1e3 * s.wall_s);
    if (dump_timeline && s.active > 0 && s.step % config.output.dump_timeline_every == 0)
      tasks::write_timeline_csv(engine.records_graph(), engine.task_types(), engine.last_records(),
                                engine.rank(), s.step,
                                fmt::format("{}/timeline_step{:06d}{}.csv", config.output.directory, s.step, rank_suffix),
                                exchange_interval());
    if (config.output.statistics_every > 0 && (engine.steps() % config.output.statistics_every == 0 || engine.finished())) {
      engine.gather_state();  // on every rank alike, though only rank 0 writes
      if (statistics) write_statistics();
    }
    if (engine.ti_current() == ti_out && !engine.finished()) {
      write();
      ++next_output;
      ti_out = next_output_ticks();
      skip_past_outputs();
    }
    if (engine.finished()) break;
    const double minutes = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_restart).count() / 60.0;
    bool restart_due = (config.restart.every_steps > 0 && engine.steps() % config.restart.every_steps == 0) ||
                       (config.restart.every_minutes > 0 && minutes >= config.restart.every_minutes);
    // Clocks and signals differ between ranks: they decide together.
    const bool terminate = engine.any_rank(g_terminate != 0);
    restart_due = engine.any_rank(restart_due);
    if (restart_due && !restart_wanted) {
      restart_wanted = true;
      wanted_since = engine.steps();
    }
    if (terminate || (restart_wanted && engine.steps() - wanted_since >= kMostStepsWaiting)) {
      write_restart_now();
    } else if (restart_wanted && s.recut_at_end) {
      save_restart();
    }
    if (terminate) {
      if (io_rank)
        fmt::print(stderr, "stopped by SIGTERM at step {}; continue with: fountain run {} --restart\n", engine.steps(),
                 params.origin());
      summary.terminated = true;
      break;
    }
    if (abandon_after_steps > 0 && engine.steps() >= abandon_after_steps) {
      if (io_rank) fmt::print(stderr, "abandoned after step {}, as asked: nothing more written\n", engine.steps());
      summary.abandoned = true;
      break;
    }
  }
  engine.set_after_rebuild({});  // it refers to this function's locals
  if (!summary.terminated && !summary.abandoned) write();
  summary.steps = engine.steps();
  summary.final_time = engine.time();
  summary.ranks = engine.ranks();
  summary.partitions = engine.partitions();
  summary.bytes_sent = engine.bytes_sent();
  summary.messages_sent = engine.messages_sent();
  summary.graph_s = engine.graph_seconds();
  summary.exchange_s = engine.exchange_seconds();
  summary.halo_mode = engine.halo_mode();
  summary.held_share = engine.held_share();
  summary.h_max_capped = engine.h_max_capped();
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return summary;
}

}  // namespace fountain
