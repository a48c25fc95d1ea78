// Whole-run benchmark of a periodic cosmological box of gas and dark matter from z = 49 to z = 0 without cooling: wall
// time, steps, time per task kind (mesh, tree, hydro) and memory per particle, written as JSON. Usage:
// fountain_cosmo_bench [-n 64] [--box 64] [--threads N] [--a-end 1] [--max-dln-a 0.01] [--mesh-cells M]
// [--viscosity-reconstruction] [--rebuild-skin S] [--json FILE].
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <fstream>
#include <map>

#include "BenchMain.hpp"
#include "engine/Engine.hpp"
#include "gravity/LongRangeForce.hpp"
#include "ics/CosmologicalBox.hpp"
#include "tasks/MpiSession.hpp"

using namespace fountain;

namespace {
int run(int argc, char** argv, const tasks::MpiSession& mpi) {
  CLI::App app{"Fountain cosmological box benchmark"};
  int threads = 1, per_side = 64;
  double box = 64.0, a_end = 1.0, max_dln_a = 0.01, z_start = 49.0;
  std::string json_path;
  app.add_option("-n,--per-side", per_side, "particles per side and species (a power of two)");
  app.add_option("--box", box, "box side, Mpc/h");
  app.add_option("-t,--threads", threads);
  app.add_option("--z-start", z_start);
  app.add_option("--a-end", a_end);
  app.add_option("--max-dln-a", max_dln_a, "time_integration.max_dln_a");
  int mesh_cells = 0;
  app.add_option("--mesh-cells", mesh_cells, "gravity.mesh_cells (0: chosen from the particle count)");
  double skin = SpaceConfig::default_skin(true);
  app.add_option("--rebuild-skin", skin, "space.rebuild_skin (default: a comoving run's)");
  bool reconstruction = false;
  app.add_flag("--viscosity-reconstruction", reconstruction, "hydro.viscosity_reconstruction");
  app.add_option("--json", json_path);
  CLI11_PARSE(app, argc, argv);

  const auto t0 = std::chrono::steady_clock::now();
  ics::CosmologicalBoxParams p;
  p.level = static_cast<int>(std::lround(std::log2(per_side)));
  p.box = box;
  p.a_start = 1.0 / (1.0 + z_start);
  ics::CosmologicalBox ic = ics::make_cosmological_box(p, Units{});
  RunConfig c;
  c.threads = threads;
  c.space.periodic = true;
  c.space.box_size = {box, box, box};
  c.comoving.enabled = true;
  c.comoving.cosmology = p.cosmology;
  c.comoving.a_begin = p.a_start;
  c.comoving.a_end = a_end;
  c.set_comoving_times();
  c.integration.dt_max = 1.0;  // no cooling: the physical step is bound by ln a alone
  c.integration.max_dln_a = max_dln_a;
  c.gravity.enabled = true;
  c.gravity.G = Units{}.gravitational_constant();
  const double spacing = box / per_side;
  c.gravity.softening_dark_matter = spacing / 25.0;  // comoving, a usual choice
  c.gravity.softening_gas = 0.5 * c.gravity.softening_dark_matter;
  c.gravity.mesh_cells = mesh_cells;
  c.hydro.viscosity_reconstruction = reconstruction;
  c.space.skin = skin;
  const std::size_t n = ic.gas.size() + ic.dark_matter.size();
  Engine e(c, to_run_particles(std::move(ic.gas)), to_run_particles(std::move(ic.dark_matter)));
  e.initialise();
  e.set_record_timeline(true);
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::map<std::string, double> kind_s;
  double updates = 0, busy = 0;
  // Wall time in the step's task graphs, and in rebuilds (outside them), since the start.
  const double rebuild_s_before = e.rebuild_seconds(), graph_s_before = e.graph_seconds();
  const auto rebuilds_before = e.space().rebuild_count();
  const auto t1 = std::chrono::steady_clock::now();
  double next_report = 60.0;
  while (!e.finished()) {
    const StepInfo s = e.step();
    // A line a minute on stderr, so that a long run shows how far it is.
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    if (elapsed >= next_report) {
      fmt::print(stderr, "{:.0f} s: step {}, a = {:.4f}\n", elapsed, e.steps(), std::exp(e.time()));
      next_report += 60.0;
    }
    updates += static_cast<double>(s.active);
    busy += s.tasks_busy_s;
    const auto& records = e.last_records();
    for (std::size_t t = 0; t < records.size(); ++t) {
      const auto& r = records[t];
      if (r.end_ns <= r.start_ns) continue;
      const auto& type = e.task_types()[e.records_graph().task(static_cast<int>(t)).type];
      kind_s[type.category == "gravity" ? type.name + "/" + type.subtype : type.category] +=
          1e-9 * static_cast<double>(r.end_ns - r.start_ns);
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  std::string kinds;
  for (const auto& [name, s] : kind_s) kinds += fmt::format("\"{}\": {:.3f}, ", name, s);
  const std::string json = fmt::format(
      "{{\"problem\": \"cosmological_box\", \"particles_per_side\": {}, \"particles\": {}, \"box_mpc_h\": {}, "
      "\"z_start\": {}, \"a_end\": {}, \"max_dln_a\": {}, \"mesh_cells\": {}, \"viscosity_reconstruction\": {}, \"rebuild_skin\": {}, \"threads\": {}, \"setup_s\": {:.3f}, \"wall_s\": {:.3f}, "
      "\"steps\": {}, \"particle_updates\": {:.6g}, \"task_seconds\": {{{}\"outside_tasks\": {:.3f}}}, "
      "\"graph_wall_s\": {:.3f}, \"rebuilds\": {}, \"rebuild_wall_s\": {:.3f}, \"peak_rss_bytes_per_particle\": {:.1f}}}\n",
      per_side, n, box, z_start, a_end, max_dln_a, gravity::LongRangeForce::choose_cells(mesh_cells, n), reconstruction, c.space.skin,
      e.threads(), setup, wall, e.steps(), updates, kinds,
      wall * e.threads() - busy, e.graph_seconds() - graph_s_before, e.space().rebuild_count() - rebuilds_before,
      e.rebuild_seconds() - rebuild_s_before, static_cast<double>(ru.ru_maxrss) * 1024.0 / static_cast<double>(n));
  bench::report_json(mpi, json, json_path);
  return 0;
}
}  // namespace

int main(int argc, char** argv) { return bench::main_reporting_errors(argc, argv, run); }
