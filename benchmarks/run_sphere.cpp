// Whole-run benchmark of the paper's rotating sphere (gravity, cooling, MSPH, optionally star
// formation and MFB): wall time, updates per second and time per task category over a fixed
// stretch of simulated time, written as JSON. Usage: fountain_sphere_bench [-n 8000]
// [--threads N] [--t-end T] [--measure-from T0] [--star-formation --eps-cold 0.4 --eps-hot 0.4]
// [--ic FILE] [--json FILE]; with --measure-from the run before T0 is not timed (star formation
// starts only once the disc has formed); with --ic the run starts from that file's particles
// (a snapshot of the collapsed sphere, say) instead of the generated sphere, its clock at zero.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>

#include "engine/Engine.hpp"
#include "BenchMain.hpp"
#include "RankFields.hpp"
#include "tasks/MpiSession.hpp"
#include "ics/RotatingSphere.hpp"
#include "io/InitialConditions.hpp"

using namespace fountain;

namespace {
// Rank 0 writes the JSON.
int run(int argc, char** argv, const tasks::MpiSession& mpi) {
  CLI::App app{"Fountain rotating-sphere benchmark"};
  int threads = 1, per_species = 8000;
  double t_end = 5.0e-5, softening = 0.001;
  bool msph = true, cooling = true, star_formation = false;
  double measure_from = 0.0, eps_cold = 0.4, eps_hot = 0.4;
  std::string json_path, ic_path;
  app.add_option("-n,--particles", per_species, "particles per species");
  app.add_option("-t,--threads", threads);
  bool pin = false;
  app.add_flag("--pin", pin, "run.pin_threads: each task thread on a core of its own");
  app.add_option("--t-end", t_end, "simulated time to run (internal units; 977.8 Gyr each)");
  app.add_option("--softening", softening, "dark matter softening (Mpc/h)");
  app.add_option("--msph", msph);
  app.add_option("--cooling", cooling);
  double skin = SpaceConfig{}.skin;
  app.add_option("--skin", skin, "space.rebuild_skin");
  app.add_option("--json", json_path);
  app.add_option("--ic", ic_path, "start from this HDF5 file's particles (GADGET layout, e.g. a snapshot)")
      ->check(CLI::ExistingFile);
  app.add_flag("--star-formation", star_formation, "star formation and MFB on");
  app.add_option("--eps-cold", eps_cold);
  app.add_option("--eps-hot", eps_hot);
  app.add_option("--measure-from", measure_from, "time from which steps are timed (internal units)");
  bool assemble_tree = false;
  app.add_flag("--assemble-tree", assemble_tree, "domain.assemble_gravity_tree: each rank's tree assembled across ranks");
  CLI11_PARSE(app, argc, argv);

  ics::RotatingSphereParams sp;
  sp.particles_per_species = per_species;
  ics::RotatingSphereIC ic;
  if (ic_path.empty()) {
    ic = ics::rotating_sphere(sp);
  } else {
    io::InitialConditions file = io::read_initial_conditions(ic_path);
    ic.gas = std::move(file.gas);
    ic.dm = std::move(file.dm);
    per_species = static_cast<int>(ic.gas.size());
  }
  RunConfig c;
  c.t_end = t_end;
  c.threads = threads;
  c.pin_threads = pin;
  c.hydro.msph = msph;
  c.space.skin = skin;
  c.integration.dt_min = 1e-12;
  c.integration.dt_max = 1e-6;
  c.gravity.enabled = true;
  c.gravity.G = Units{}.gravitational_constant();
  c.gravity.softening_dark_matter = softening;
  c.gravity.softening_gas = 0.5 * softening;
  c.cooling.enabled = cooling;
  c.star_formation.enabled = star_formation;
  c.feedback.eps_cold = eps_cold;
  c.feedback.eps_hot = eps_hot;
  c.assemble_gravity_tree = assemble_tree;
  const std::size_t n = ic.gas.size() + ic.dm.size();

  const auto t0 = std::chrono::steady_clock::now();
  Engine e(c, std::move(ic.gas), std::move(ic.dm));
  e.initialise();
  while (!e.finished() && e.time() < measure_from) e.step();
  e.set_record_timeline(true);
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::map<std::string, double> category_s;
  double tasks_wall = 0, tasks_busy = 0, updates = 0;
  const long long steps_before = e.steps();
  const double time_before = e.time();
  const double stars_before = e.star_formation_total().mass_formed;
  const bench::RankCounters counters = bench::RankCounters::of(e);
  const auto t1 = std::chrono::steady_clock::now();
  while (!e.finished()) {
    const StepInfo s = e.step();
    updates += static_cast<double>(s.active);
    tasks_wall += s.tasks_wall_s;
    tasks_busy += s.tasks_busy_s;
    const auto& records = e.last_records();
    for (std::size_t t = 0; t < records.size(); ++t) {
      const auto& r = records[t];
      if (r.end_ns <= r.start_ns) continue;
      category_s[e.task_types()[e.records_graph().task(static_cast<int>(t)).type].category] +=
          1e-9 * static_cast<double>(r.end_ns - r.start_ns);
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  std::string categories;
  for (const auto& [name, s] : category_s) categories += fmt::format("\"{}\": {:.4f}, ", name, s);
  const double thread_time = wall * e.threads();
  const std::string json = fmt::format(
      "{{\"problem\": \"rotating_sphere\", \"initial_conditions\": \"{}\", \"particles_per_species\": {}, "
      "\"particles\": {}, \"threads\": {}, "
      "\"msph\": {}, \"cooling\": {}, \"star_formation\": {}, \"eps_cold\": {}, \"eps_hot\": {}, "
      "\"measured_from\": {}, \"t_end\": {}, \"mass_formed_measured\": {:.4g}, \"promotions\": {}, "
      "\"setup_s\": {:.3f}, \"wall_s\": {:.3f}, \"steps\": {}, "
      "\"updates_per_s\": {:.4g}, \"task_seconds_by_category\": {{{}\"outside_tasks\": {:.4f}}}, "
      "\"tasks_busy_share_of_thread_time\": {:.4f}, \"peak_rss_bytes_per_particle\": {:.1f}, {}}}\n",
      ic_path.empty() ? "generated" : std::filesystem::path(ic_path).filename().string(), per_species, n,
      e.threads(), msph, cooling, star_formation, eps_cold, eps_hot, time_before, t_end,
      e.star_formation_total().mass_formed - stars_before, e.star_formation_total().promotions, setup, wall,
      e.steps() - steps_before, updates / wall, categories,
      thread_time - tasks_busy, tasks_wall > 0 ? tasks_busy / thread_time : 0.0,
      static_cast<double>(ru.ru_maxrss) * 1024.0 / static_cast<double>(n),
      bench::rank_fields(e, counters, e.steps() - steps_before, wall, tasks_busy));
  bench::report_json(mpi, json, json_path);
  return 0;
}
}  // namespace

int main(int argc, char** argv) { return bench::main_reporting_errors(argc, argv, run); }
