// The fountain command line: run a parameter file, write example ICs, print the parameter reference.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <exception>

#include "app/Simulation.hpp"
#include "core/Error.hpp"
#include "ics/RotatingSphere.hpp"
#include "ics/TestProblems.hpp"
#include "io/InitialConditions.hpp"
#include "params/ParameterFile.hpp"
#include "params/ParameterSchema.hpp"
#include "tasks/MpiSession.hpp"

int main(int argc, char** argv) {
  using namespace fountain;
  tasks::MpiSession mpi(&argc, &argv);
  CLI::App app{"Fountain: SPH + tree gravity for galaxy formation (Marri & White 2003 physics)"};
  app.require_subcommand(1);

  auto* run = app.add_subcommand("run", "Run the problem of a YAML parameter file");
  std::string param_path;
  int threads = -1;
  bool quiet = false, restart = false;
  run->add_option("params", param_path, "Parameter file")->required();
  run->add_option("-t,--threads", threads, "Worker threads (overrides run.threads)");
  run->add_flag("-q,--quiet", quiet, "No per-step progress lines");
  run->add_flag("-r,--restart", restart, "Continue from <output.directory>/restart.hdf5");
  long long abandon_after = 0;
  run->add_option("--abandon-after-steps", abandon_after,
                  "Stop once the step count (as printed, continued across restarts) reaches this and write nothing "
                  "more, as a run killed there would (to test restarts)")
      ->check(CLI::PositiveNumber);

  auto* ic = app.add_subcommand("ic", "Write the initial conditions of a validation problem");
  std::string problem, out_path;
  int resolution = 0;
  double gamma = 5.0 / 3.0;
  ics::RotatingSphereParams sphere;
  ic->add_option("problem", problem, "sod | sedov | gresho | evrard | sphere")
      ->required()
      ->check(CLI::IsMember({"sod", "sedov", "gresho", "evrard", "sphere"}));
  ic->add_option("-o,--output", out_path, "Output HDF5 file")->required();
  ic->add_option("-n,--resolution", resolution,
                 "Lattice cells per unit length (sod: left state; sedov, gresho: per box side; evrard: per radius); "
                 "sphere: particles per species (default 4000)");
  ic->add_option("--gamma", gamma, "Adiabatic index");
  ic->add_option("--mass", sphere.total_mass, "sphere: total mass, gas + DM [Msun/h]")->capture_default_str();
  ic->add_option("--radius", sphere.radius, "sphere: radius [Mpc/h]")->capture_default_str();
  ic->add_option("--spin", sphere.spin, "sphere: spin parameter lambda = J|E|^(1/2)/(G M^(5/2))")->capture_default_str();
  ic->add_option("--thermal-fraction", sphere.thermal_fraction, "sphere: gas specific energy u over |W|/M")
      ->capture_default_str();
  ic->add_option("--gas-fraction", sphere.gas_fraction, "sphere: gas mass over total mass")->capture_default_str();

  auto* params_cmd = app.add_subcommand("params", "Print the parameter reference (Markdown)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  // Across ranks, a failure on one rank must stop the others, which would otherwise wait for
  // it in their next exchange; every rank reads the same input, so input errors are met by all.
  auto fail = [&](int code) {
    if (mpi.size() > 1) mpi.abort(code);
    return code;
  };
  if (mpi.size() > 1 && !*run) {
    if (mpi.rank() == 0) fmt::print(stderr, "error: only `fountain run` runs across MPI ranks; start the others alone\n");
    return 2;
  }

  try {
    if (*run) {
      const ParameterFile params = ParameterFile::load(param_path);
      const RunSummary s = run_simulation(params, quiet, threads, restart, abandon_after);
      // Stopped by SIGTERM after writing a restart file: EX_TEMPFAIL, so that job scripts can
      // tell a stopped run (continue it with --restart) from a finished one.
      if (s.terminated) return 75;
      if (s.abandoned) return 0;
      if (mpi.rank() == 0)
        fmt::print(stderr, "done: {} steps to t = {:.6g}, {} snapshots, {:.2f} s\n", s.steps, s.final_time,
                 s.snapshots, s.wall_s);
      if (mpi.rank() == 0 && s.ranks > 1)
        fmt::print(stderr,
                   "ranks: {}, cell owners chosen {} times; rank 0 sent {:.3g} MB in {} messages, spent {:.2f} s in "
                   "task graphs and {:.2f} s in the exchanges after them\n",
                   s.ranks, s.partitions, 1e-6 * static_cast<double>(s.bytes_sent), s.messages_sent, s.graph_s,
                   s.exchange_s);
      if (mpi.rank() == 0 && s.halo_mode)
        fmt::print(stderr, "halo mode: rank 0 kept {:.1f}% of the leaves current (mean over the recuts)\n",
                   100.0 * s.held_share);
    } else if (*ic) {
      if (problem == "sphere") {
        if (resolution > 0) sphere.particles_per_species = resolution;
        const ics::RotatingSphereIC s = ics::rotating_sphere(sphere);
        // Isolated: centred on the origin; BoxSize is the enclosing cube's side (informative).
        const double side = 2.0 * sphere.radius;
        io::write_initial_conditions(out_path, s.gas, s.dm, {side, side, side}, false);
        fmt::print(stderr,
                   "wrote {} ({} gas + {} dark matter particles; omega = {:.6g} km/s per Mpc/h, u = {:.6g} (km/s)^2, "
                   "W = {:.6g}, spin = {:.6g})\n",
                   out_path, s.gas.size(), s.dm.size(), s.omega, s.u, s.potential_energy, s.spin);
      } else {
        ics::ProblemIC p;
        if (problem == "sod") p = ics::sod_shock(resolution > 0 ? resolution : 32, gamma);
        else if (problem == "sedov") p = ics::sedov_blast(resolution > 0 ? resolution : 24, gamma);
        else if (problem == "evrard") p = ics::evrard_sphere(resolution > 0 ? resolution : 8);
        else p = ics::gresho_vortex(resolution > 0 ? resolution : 32, gamma);
        io::write_initial_conditions(out_path, p.gas, p.box_size, p.periodic);
        fmt::print(stderr, "wrote {} ({} gas particles, box {} x {} x {})\n", out_path, p.gas.size(), p.box_size.x,
                   p.box_size.y, p.box_size.z);
      }
    } else if (*params_cmd) {
      fmt::print("{}", parameter_reference_markdown());
    }
  } catch (const InputError& e) {
    fmt::print(stderr, "{}error: {}\n", mpi.size() > 1 ? fmt::format("rank {}: ", mpi.rank()) : "", e.what());
    return fail(2);
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}internal error: {}\n", mpi.size() > 1 ? fmt::format("rank {}: ", mpi.rank()) : "", e.what());
    return fail(3);
  }
  return 0;
}
