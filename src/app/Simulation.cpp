#include "app/Simulation.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "core/Error.hpp"
#include "engine/Engine.hpp"
#include "io/InitialConditions.hpp"
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
void check_output_directory(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(fmt::format("output directory '{}' cannot be created: {}", dir,
                                 ec ? ec.message() : "a file of that name exists"));
  const fs::path probe = fs::path(dir) / ".fountain_write_test";
  {
    std::ofstream out(probe);
    if (!(out << "ok") || !out.flush())
      throw InputError(fmt::format("output directory '{}' is not writable", dir));
  }
  fs::remove(probe, ec);
}

std::string resolve_ic_path(const ParameterFile& params) {
  fs::path ic = params.text("initial_conditions.file");
  if (ic.is_relative()) ic = fs::path(params.origin()).parent_path() / ic;
  return ic.lexically_normal().string();
}

}  // namespace

RunSummary run_simulation(const ParameterFile& params, bool quiet, int threads_override) {
  const auto t_start = std::chrono::steady_clock::now();
  RunConfig config = RunConfig::from(params);
  if (threads_override >= 0) config.threads = threads_override;
  check_output_directory(config.output.directory);
  io::InitialConditions ic = io::read_initial_conditions(resolve_ic_path(params));
  config.space.box_size = ic.box_size;
  if (config.space.periodic && !(ic.box_size.x > 0 && ic.box_size.y > 0 && ic.box_size.z > 0))
    throw InputError(fmt::format("{}: periodic run needs a positive /Header/BoxSize", resolve_ic_path(params)));
  if (config.space.periodic)
    for (std::size_t i = 0; i < ic.gas.size(); ++i)
      for (int k = 0; k < 3; ++k)
        if (ic.gas.x[i][k] < -ic.box_size[k] || ic.gas.x[i][k] > 2 * ic.box_size[k])
          throw InputError(fmt::format("{}: particle ID {} lies far outside the periodic box", resolve_ic_path(params),
                                       ic.gas.id[i]));

  Engine engine(config, std::move(ic.gas));
  const bool dump_timeline = config.output.dump_timeline_every > 0;
  engine.set_record_timeline(dump_timeline || config.output.dump_task_graph);
  engine.initialise();

  io::SnapshotInfo info;
  info.box_size = config.space.box_size;
  info.periodic = config.space.periodic;
  info.units = config.units;
  info.gamma = config.hydro.gamma;
  info.parameters_yaml = config.parameters_yaml;
  info.git_revision = git_revision();
  info.build_options = build_options();

  RunSummary summary;
  auto write = [&] {
    engine.drift_all();
    info.time = engine.time();
    info.step = engine.steps();
    const std::string path = fmt::format("{}/{}_{:04d}.hdf5", config.output.directory, config.output.basename,
                                         summary.snapshots);
    io::write_snapshot(path, engine.gas(), info);
    if (!quiet) fmt::print(stderr, "snapshot {} at t = {:.6g}\n", path, info.time);
    ++summary.snapshots;
  };
  if (config.output.dump_task_graph) {
    tasks::write_dot(engine.graph(), engine.task_types().registry, config.output.directory + "/task_graph.dot");
    tasks::write_dependency_csv(engine.graph(), engine.task_types().registry,
                                config.output.directory + "/dependency_graph_0.csv");
  }
  write();

  const double dt_out = config.output.delta_time;
  int next_output = 1;
  auto next_output_ticks = [&] {
    if (dt_out <= 0.0) return TimeLine::ticks;
    const double t = config.t_begin + next_output * dt_out;
    return t >= config.t_end ? TimeLine::ticks : engine.to_ticks(t);
  };
  IntegerTime ti_out = next_output_ticks();
  while (!engine.finished()) {
    if (config.max_steps > 0 && engine.steps() >= config.max_steps) break;
    const StepInfo s = engine.step(ti_out);
    if (!quiet)
      fmt::print(stderr, "step {:6d}  t = {:<12.6g} dt = {:<11.4g} active = {:<8d} {}wall = {:.3f} ms\n", s.step,
                 s.time, s.dt, s.active, s.rebuilt ? "rebuilt " : "", 1e3 * s.wall_s);
    if (dump_timeline && s.active > 0 && s.step % config.output.dump_timeline_every == 0)
      tasks::write_timeline_csv(engine.graph(), engine.task_types().registry, engine.last_records(), 0, s.step,
                                fmt::format("{}/timeline_step{:06d}.csv", config.output.directory, s.step));
    if (engine.ti_current() == ti_out && !engine.finished()) {
      write();
      ++next_output;
      ti_out = next_output_ticks();
    }
  }
  write();
  summary.steps = engine.steps();
  summary.final_time = engine.time();
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return summary;
}

}  // namespace fountain
