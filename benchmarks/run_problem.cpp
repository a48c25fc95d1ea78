// Whole-run benchmark of a standard hydro problem: wall time, step costs, parallel share,
// peak memory and accuracy, written as JSON. Usage: fountain_run_bench sod|sedov|gresho
// [--threads N] [--resolution N] [--courant-criterion syw|signal_velocity] [--viscosity-reconstruction]
// [--json FILE] [--step-log FILE]
// [--ic FILE]
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <stdexcept>

#include "analysis/HydroReference.hpp"
#include "io/InitialConditions.hpp"
#include "engine/Engine.hpp"
#include "BenchMain.hpp"
#include "RankFields.hpp"
#include "tasks/MpiSession.hpp"
#include "ics/TestProblems.hpp"

using namespace fountain;

namespace {
// Rank 0 writes the JSON.
int run(int argc, char** argv, const tasks::MpiSession& mpi) {
  CLI::App app{"Fountain whole-run benchmark"};
  std::string problem, json_path;
  int threads = 1, resolution = 0, neighbours = 48, split = 256;
  double t_end = 0;
  app.add_option("problem", problem)->required()->check(CLI::IsMember({"sod", "sedov", "gresho"}));
  app.add_option("-t,--threads", threads);
  bool pin = false;
  app.add_flag("--pin", pin, "run.pin_threads: each task thread on a core of its own");
  app.add_option("-n,--resolution", resolution, "lattice cells per unit length");
  app.add_option("--neighbours", neighbours);
  app.add_option("--t-end", t_end);
  app.add_option("--split", split, "space.cell_split_size");
  double viscosity_alpha = HydroParams{}.viscosity_alpha;
  app.add_option("--viscosity-alpha", viscosity_alpha, "hydro.viscosity_alpha (the paper's 1.3 by default)");
  bool reconstruction = false;
  app.add_flag("--viscosity-reconstruction", reconstruction, "hydro.viscosity_reconstruction");
  double neighbours_tolerance = HydroParams{}.neighbours_tolerance;
  app.add_option("--neighbours-tolerance", neighbours_tolerance, "hydro.neighbours_tolerance");
  double skin = SpaceConfig{}.skin;
  app.add_option("--skin", skin, "space.rebuild_skin");
  double repartition_imbalance = RunConfig{}.repartition_imbalance;
  app.add_option("--repartition-imbalance", repartition_imbalance, "domain.repartition_imbalance (across ranks)");
  long long repartition_min_steps = RunConfig{}.repartition_min_steps;
  app.add_option("--repartition-min-steps", repartition_min_steps, "domain.repartition_min_steps (across ranks)");
  double courant = HydroParams{}.courant;
  app.add_option("--courant", courant, "hydro.courant (alpha_c)");
  std::string criterion = "syw";
  app.add_option("--courant-criterion", criterion, "time_integration.courant_criterion")
      ->check(CLI::IsMember({"syw", "signal_velocity"}));
  app.add_option("--json", json_path);
  std::string step_log_path;
  app.add_option("--step-log", step_log_path,
                 "CSV of every step's active particles, graph wall time and task time (each rank: FILE.rank<R>)");
  std::string ic_path;
  app.add_option("--ic", ic_path,
                 "the problem's particles from this file (`fountain ic`), each rank reading its share as `fountain "
                 "run` does, rather than made in memory on every rank: the peak memory is then a run's");
  CLI11_PARSE(app, argc, argv);

  const double gamma = 5.0 / 3.0;
  ics::ProblemIC ic;
  double dt_max = 0.01;
  const bool made = ic_path.empty();
  if (problem == "sod") {
    if (made) ic = ics::sod_shock(resolution > 0 ? resolution : 64, gamma);
    if (t_end <= 0) t_end = 0.2;
  } else if (problem == "sedov") {
    if (made) ic = ics::sedov_blast(resolution > 0 ? resolution : 50, gamma);
    if (t_end <= 0) t_end = 0.05;
    dt_max = 5e-4;
  } else {
    if (made) ic = ics::gresho_vortex(resolution > 0 ? resolution : 64, gamma);
    if (t_end <= 0) t_end = 1.0;
  }
  std::size_t n = ic.gas.size();
  std::optional<Engine::GasShare> share;
  if (!made) {
    io::IcReadOptions options;
    options.share_rank = mpi.rank();
    options.share_ranks = mpi.size();
    io::InitialConditions file = io::read_initial_conditions(ic_path, options);
    ic.gas = std::move(file.gas);
    ic.box_size = file.box_size;
    n = file.gas_total;
    if (mpi.size() > 1) share = Engine::GasShare{file.gas_first, file.gas_total, {}, true, file.dm_total, {}, file.dm_first};
  }
  RunConfig c;
  c.t_end = t_end;
  c.threads = threads;
  c.pin_threads = pin;
  c.hydro.neighbours = neighbours;
  c.hydro.viscosity_alpha = viscosity_alpha;
  c.hydro.viscosity_reconstruction = reconstruction;
  c.hydro.neighbours_tolerance = neighbours_tolerance;
  c.hydro.msph = false;
  c.hydro.limiter_bins = 1;
  c.hydro.courant = courant;
  c.hydro.courant_criterion =
      criterion == "signal_velocity" ? CourantCriterion::SignalVelocity : CourantCriterion::Syw;
  c.integration.dt_min = 1e-12;
  c.integration.dt_max = dt_max;
  c.space.periodic = true;
  c.space.box_size = ic.box_size;
  c.space.split_size = split;
  c.space.skin = skin;
  c.repartition_imbalance = repartition_imbalance;
  c.repartition_min_steps = repartition_min_steps;

  const auto t0 = std::chrono::steady_clock::now();
  Engine e(c, std::move(ic.gas), {}, share);
  e.initialise();
  const bench::RankCounters counters = bench::RankCounters::of(e);
  const long long steps_before = e.steps();
  const auto t_steps = std::chrono::steady_clock::now();
  double full_step_s = 0, tasks_wall = 0, tasks_busy = 0, updates = 0;
  long long full_steps = 0;
  // Per step, so that two processes' (or two ranks') speeds can be set side by side step by
  // step (benchmarks/core_noise.py).
  std::ofstream step_log;
  const std::string step_log_file =
      e.ranks() > 1 ? fmt::format("{}.rank{}", step_log_path, e.rank()) : step_log_path;
  if (!step_log_path.empty()) {
    step_log.open(step_log_file);
    if (!step_log) throw std::runtime_error(fmt::format("cannot write the step log {}", step_log_file));
    step_log << "step,active,rebuilt,step_wall_s,tasks_wall_s,tasks_busy_s\n";
  }
  while (!e.finished()) {
    const StepInfo s = e.step();
    if (step_log.is_open())
      step_log << fmt::format("{},{},{},{:.7f},{:.7f},{:.7f}\n", s.step, s.active, s.rebuilt ? 1 : 0, s.wall_s,
                              s.tasks_wall_s, s.tasks_busy_s);
    updates += static_cast<double>(s.active);
    tasks_wall += s.tasks_wall_s;
    tasks_busy += s.tasks_busy_s;
    if (s.active == n && !s.rebuilt) {
      full_step_s += s.wall_s;
      ++full_steps;
    }
  }
  // A log cut short by a full disk would read as a shorter run.
  if (step_log.is_open() && !step_log.flush())
    throw std::runtime_error(fmt::format("could not write the whole step log {}", step_log_file));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double steps_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_steps).count();
  const std::string ranks = bench::rank_fields(e, counters, e.steps() - steps_before, steps_wall, tasks_busy);
  e.drift_all();
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  const double peak_bytes = static_cast<double>(ru.ru_maxrss) * 1024.0;

  std::string accuracy;
  if (problem == "sod") {
    const analysis::SodExact exact(std::string(FOUNTAIN_SOURCE_DIR) + "/data/hydro_tests/sod_exact_gamma5_3_t0.2.txt");
    accuracy = fmt::format("\"sod_density_l1\": {:.6f}", analysis::sod_density_l1(e.gas(), exact));
  } else if (problem == "sedov") {
    const double r = analysis::sedov_shock_radius(e.gas(), {0.5, 0.5, 0.5}, {1, 1, 1});
    accuracy = fmt::format("\"shock_radius\": {:.5f}, \"shock_radius_exact\": {:.5f}", r,
                           analysis::sedov_exact_radius(1.0, 1.0, t_end));
  } else {
    accuracy = fmt::format("\"gresho_velocity_l1\": {:.6f}", analysis::gresho_velocity_l1(e.gas()));
  }
  const double per_particle_us = full_steps > 0 ? 1e6 * full_step_s / full_steps / static_cast<double>(n) : 0.0;
  const std::string json = fmt::format(
      "{{\"problem\": \"{}\", \"courant_criterion\": \"{}\", \"viscosity_reconstruction\": {}, \"particles\": {}, "
      "\"threads\": {}, \"neighbours\": {}, \"t_end\": {}, "
      "\"wall_s\": {:.3f}, \"steps\": {}, \"full_steps\": {}, \"full_step_us_per_particle\": {:.4f}, "
      "\"updates_per_s\": {:.4g}, \"tasks_busy_share_of_thread_time\": {:.4f}, \"peak_rss_bytes_per_particle\": {:.1f}, "
      "{}, {}}}\n",
      problem, criterion, reconstruction, n, e.threads(), neighbours, t_end, wall, e.steps(), full_steps, per_particle_us, updates / wall,
      tasks_wall > 0 ? tasks_busy / (tasks_wall * e.threads()) : 0.0, peak_bytes / static_cast<double>(n), accuracy, ranks);
  bench::report_json(mpi, json, json_path);
  return 0;
}
}  // namespace

int main(int argc, char** argv) { return bench::main_reporting_errors(argc, argv, run); }
