#include "app/RunSetup.hpp"

#include <fmt/format.h>

#include <cmath>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <tuple>
#include <vector>

#include <unistd.h>

#include "app/ComovingStart.hpp"
#include "app/Simulation.hpp"
#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

namespace fs = std::filesystem;

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

RunStart prepare_run(const ParameterFile& params, const RunOptions& options) {
  RunStart start;
  RunConfig& config = start.config;
  config = RunConfig::from(params);
  if (options.threads)
    config.threads = static_cast<int>(
        std::stoll(ParameterFile::check("run.threads", std::to_string(*options.threads), "option -t,--threads")));
  const std::string ic_path = resolve_ic_path(params);
  check_output_directory(params, config.output.directory);
  // Rank 0 holds the folder for the whole run; it alone writes snapshots and the master files.
  if (options.rank == 0) {
    start.lock = std::make_unique<OutputFolderLock>(config.output.directory);
    if (!start.lock->unsupported().empty()) fmt::print(stderr, "warning: {}\n", start.lock->unsupported());
    if (!start.lock->stale_holder().empty())
      fmt::print(stderr, "note: took over the lock of {} left by a run that did not end ({})\n",
                 config.output.directory, start.lock->stale_holder());
    guard_output_folder(config.output.directory, config.output.basename, {ic_path, params.origin()}, options.restart,
                        options.overwrite);
  }
  io::IcReadOptions read_options;
  read_options.cosmological = config.comoving.enabled;
  start.ic = io::read_initial_conditions(ic_path, read_options);
  io::InitialConditions& ic = start.ic;
  // A snapshot used as initial conditions carries its time: the run goes on from there.
  if (config.comoving.enabled) {
    to_comoving_variables(ic, config, params, ic_path);
  } else if (!params.was_given("run.t_begin")) {
    config.t_begin = ic.time;
    config.check_times(params, fmt::format("/Header/Time of {}", ic_path));
  } else if (ic.time != config.t_begin && options.rank == 0) {
    fmt::print(stderr, "warning: {} = {} differs from /Header/Time = {} of {}; the run starts at {}\n",
               params.where("run.t_begin"), config.t_begin, ic.time, ic_path, config.t_begin);
  }
  if (config.space.periodic) check_fits_periodic_box(ic, ic_path);
  check_distinct_positions(ic, config.space.periodic, ic_path);
  if (options.restart) {
    io::RestartState& state = start.restart;
    state = io::read_restart(restart_path(params));
    check_same_parameters(state, params, restart_path(params));
    const std::size_t state_dm = state.dm.size() - state.dm.count(Species::Star);
    if (state_dm != ic.dm.size())
      throw InputError(fmt::format("{}: restart file holds {} dark matter particles, but the initial conditions {} "
                                   "have {}",
                                   restart_path(params), state_dm, ic_path, ic.dm.size()));
    ic.gas = std::move(state.gas);
    ic.dm = std::move(state.dm);
  }
  config.space.box_size = ic.box_size;
  return start;
}

void start_engine(Engine& engine, const RunStart& start, const ParameterFile& params, const RunOptions& options,
                  bool quiet) {
  if (!options.restart) {
    engine.initialise();
    return;
  }
  const io::RestartState& state = start.restart;
  engine.restore(state.ti_current, state.steps, state.ti_step_begin, {state.mesh_step_bin, state.mesh_step_begin});
  engine.set_radiated_energy(state.radiated_energy);
  engine.set_star_formation_total(state.star_formation);
  if (state.next_particle_id > 0) engine.set_next_particle_id(state.next_particle_id);
  // A file written inside a step holds its end; the run goes on from the step's start.
  // (A comoving run's timeline reads ln a: it says a.)
  const double begin = engine.timeline().time(state.ti_step_begin);
  if (!quiet)
    fmt::print(stderr, "restarted from {} at {} = {:.6g}, step {}\n", restart_path(params),
               engine.config().comoving.enabled ? "a" : "t", engine.config().comoving.enabled ? std::exp(begin) : begin,
               engine.steps());
}

}  // namespace fountain
