// The fountain command line: run a parameter file, write example ICs, print the parameter reference.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <exception>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

#include "app/GroupCommand.hpp"
#include "app/IcCommand.hpp"
#include "app/MassFunctionCommand.hpp"
#include "app/ReferenceCommand.hpp"
#include "app/Simulation.hpp"
#include "cosmology/TransferFunction.hpp"
#include "core/Error.hpp"
#include "params/ParameterFile.hpp"
#include "params/ParameterSchema.hpp"
#include "tasks/MpiSession.hpp"

namespace {

constexpr const char* kCommands[] = {"run", "ic", "fof", "hop", "mass-function", "reference", "params"};

// CLI11 answers an unknown first word with "A subcommand is required": name it instead.
bool is_unknown_command(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return false;
  for (const char* c : kCommands)
    if (std::string_view(argv[1]) == c) return false;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace fountain;
  tasks::MpiSession mpi(&argc, &argv);
  CLI::App app{"Fountain: SPH + tree gravity for galaxy formation (Marri & White 2003 physics)"};
  app.require_subcommand(1);

  auto* run = app.add_subcommand("run", "Run the problem of a YAML parameter file");
  std::string param_path;
  RunOptions options;
  long long threads = 0, abandon_after = 0;
  run->add_option("params", param_path, "Parameter file")->required();
  auto* threads_opt = run->add_option("-t,--threads", threads, "Worker threads (overrides run.threads)");
  run->add_flag("-q,--quiet", options.quiet, "No per-step progress lines");
  run->add_flag("-r,--restart", options.restart, "Continue from <output.directory>/restart.hdf5");
  run->add_flag("--overwrite", options.overwrite,
                "Start afresh in an output folder that holds an earlier run's snapshots, restart files or "
                "statistics, removing them");
  auto* abandon_opt = run->add_option(
      "--abandon-after-steps", abandon_after,
      "Stop once the step count (as printed, continued across restarts) reaches this and write nothing "
      "more, as a run killed there would (to test restarts)");

  auto* ic = app.add_subcommand("ic", "Write the initial conditions of a validation problem");
  IcRequest request;
  const std::vector<std::string> transfer_names(std::begin(cosmology::kTransferKindNames),
                                                std::end(cosmology::kTransferKindNames));
  ic->add_option("problem", request.problem, "sod | sedov | gresho | evrard | sphere | cosmo | zoom")
      ->required()
      ->check(CLI::IsMember({"sod", "sedov", "gresho", "evrard", "sphere", "cosmo", "zoom"}));
  ic->add_option("-o,--output", request.output, "Output HDF5 file")->required();
  auto* resolution_opt =
      ic->add_option("-n,--resolution", request.resolution,
                     "Lattice cells per unit length (sod: left state; sedov, gresho: per box side; evrard: per radius); "
                     "sphere: particles per species (default 4000); cosmo: particles per side and species, a power "
                     "of two (default 64)");
  auto* gamma_opt = ic->add_option("--gamma", request.gamma, "Adiabatic index, in (1, 3] (sod, sedov, gresho)");
  ics::RotatingSphereParams& sphere = request.sphere;
  const std::vector<CLI::Option*> sphere_opts = {
      ic->add_option("--mass", sphere.total_mass, "sphere: total mass, gas + DM [Msun/h]")->capture_default_str(),
      ic->add_option("--radius", sphere.radius, "sphere: radius [Mpc/h]")->capture_default_str(),
      ic->add_option("--spin", sphere.spin, "sphere: spin parameter lambda = J|E|^(1/2)/(G M^(5/2))")
          ->capture_default_str(),
      ic->add_option("--thermal-fraction", sphere.thermal_fraction, "sphere: gas specific energy u over |W|/M")
          ->capture_default_str(),
      ic->add_option("--gas-fraction", sphere.gas_fraction, "sphere: gas mass over total mass")->capture_default_str()};

  ics::CosmologicalBoxParams& cosmo = request.cosmo;
  double z_start = 49.0;
  std::string transfer = "full";
  bool no_gas = false;
  const std::vector<CLI::Option*> cosmo_opts = {
      ic->add_option("--box", cosmo.box, "cosmo: box side [Mpc/h]")->capture_default_str(),
      ic->add_option("--z-start", z_start, "cosmo: starting redshift")->capture_default_str(),
      ic->add_option("--seed", cosmo.seed, "cosmo: seed of the white noise")->capture_default_str(),
      ic->add_option("--omega-m", cosmo.cosmology.omega_m, "cosmo: Omega_m")->capture_default_str(),
      ic->add_option("--omega-lambda", cosmo.cosmology.omega_lambda, "cosmo: Omega_Lambda")->capture_default_str(),
      ic->add_option("--omega-b", cosmo.cosmology.omega_b, "cosmo: Omega_b")->capture_default_str(),
      ic->add_option("--hubble", cosmo.cosmology.hubble_param, "cosmo: h")->capture_default_str(),
      ic->add_option("--sigma-8", cosmo.sigma_8, "cosmo: sigma_8 of the linear spectrum at z = 0")->capture_default_str(),
      ic->add_option("--n-s", cosmo.n_s, "cosmo: spectral index")->capture_default_str(),
      ic->add_option("--transfer", transfer, "cosmo: Eisenstein & Hu fit: full | no_wiggle | zero_baryon")
          ->check(CLI::IsMember(transfer_names))
          ->capture_default_str(),
      ic->add_option("--lpt", cosmo.lpt_order, "cosmo: Lagrangian perturbation order, 1 (Zel'dovich) or 2")
          ->check(CLI::IsMember({1, 2}))
          ->capture_default_str(),
      ic->add_flag("--no-gas", no_gas, "cosmo: dark matter only"),
      ic->add_flag("--invert-phases", cosmo.invert_phases,
                   "cosmo: the seed's field with its sign reversed (the partner of a paired run)"),
      ic->add_flag("--fix-amplitudes", cosmo.fix_amplitudes,
                   "cosmo: every mode's amplitude set to sqrt(P(k)), only its phase random (not for zoom)")};

  auto* fof = app.add_subcommand("fof", "Friends-of-friends groups of a snapshot, written as an HDF5 catalogue");
  FofRequest fof_request;
  fof->add_option("snapshot", fof_request.snapshot, "Snapshot (GADGET-layout HDF5)")->required();
  fof->add_option("-o,--output", fof_request.output, "Catalogue to write (HDF5)")->required();
  fof->add_option("-b", fof_request.b, "Linking length in mean spacings of the linking particles (from their mean mass "
                                       "and the mean density of dark matter)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  auto* fof_length = fof->add_option("--linking-length", fof_request.linking_length,
                                     "Comoving linking length instead (needed for non-cosmological snapshots)")
                         ->check(CLI::PositiveNumber);
  fof->add_option("--link-types", fof_request.linking_types,
                  "GADGET types that link (the others join their nearest linked particle within the linking length)")
      ->capture_default_str();
  fof->add_option("--min-members", fof_request.min_members, "Linking particles a group needs")->capture_default_str();
  fof->add_option("-t,--threads", fof_request.threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);

  auto* hop = app.add_subcommand("hop", "HOP groups of a snapshot's baryons, written as an HDF5 catalogue");
  HopRequest hop_request;
  hop->add_option("snapshot", hop_request.snapshot, "Snapshot (GADGET-layout HDF5)")->required();
  hop->add_option("-o,--output", hop_request.output, "Catalogue to write (HDF5)")->required();
  hop->add_option("--outer", hop_request.outer, "delta_outer in mean baryon densities")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  hop->add_option("--saddle-factor", hop_request.saddle_factor, "delta_saddle / delta_outer")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str();
  hop->add_option("--peak-factor", hop_request.peak_factor, "delta_peak / delta_outer (at least the saddle factor)")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str();
  hop->add_option("--n-dens", hop_request.n_dens, "Neighbours of the density estimate")->check(CLI::Range(2, 4096))->capture_default_str();
  hop->add_option("--n-hop", hop_request.n_hop, "Neighbours hopped among")->check(CLI::Range(2, 4096))->capture_default_str();
  hop->add_option("--n-merge", hop_request.n_merge, "Neighbours defining boundaries")->check(CLI::Range(1, 4096))->capture_default_str();
  hop->add_option("--omega-b", hop_request.omega_b, "Omega_b, if the snapshot's header lacks OmegaBaryon")->check(CLI::Range(0.0, 1.0));
  hop->add_option("-t,--threads", hop_request.threads, "Threads (default: all cores)")->check(CLI::NonNegativeNumber);

  auto* mass_function =
      app.add_subcommand("mass-function", "A friends-of-friends catalogue's halo counts against the Jenkins et al. and "
                                          "Sheth & Tormen mass functions, as a text table");
  MassFunctionRequest mf_request;
  mass_function->add_option("catalogue", mf_request.catalogue, "Catalogue of `fountain fof`")->required();
  mass_function->add_option("-o,--output", mf_request.output, "Table to write")->required();
  mass_function->add_option("--sigma-8", mf_request.sigma_8, "sigma_8 of the initial conditions' linear spectrum at z = 0")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  mass_function->add_option("--n-s", mf_request.n_s, "Their spectral index")->check(CLI::Range(-5.0, 5.0))->capture_default_str();
  mass_function->add_option("--omega-b", mf_request.omega_b,
                            "Omega_b of their transfer function (default: the catalogue's OmegaBaryon, else 0.04)")
      ->check(CLI::Range(0.0, 1.0));
  mass_function->add_option("--transfer", mf_request.transfer, "Their Eisenstein & Hu fit: full | no_wiggle | zero_baryon")
      ->check(CLI::IsMember(transfer_names))
      ->capture_default_str();
  mass_function->add_option("--log-min", mf_request.log_min, "Lowest bin edge, log10(M / (Msun/h))")->capture_default_str();
  mass_function->add_option("--log-max", mf_request.log_max, "Highest bin edge")->capture_default_str();
  mass_function->add_option("--bin-width", mf_request.width, "Bin width in dex")->check(CLI::PositiveNumber)->capture_default_str();

  IcRequest::Zoom& zoom = request.zoom;
  std::vector<int> zoom_levels;
  auto* levels_opt = ic->add_option("--levels", zoom_levels,
                                    "zoom: coarsest, parent and finest grid levels (2^level cells per side), e.g. 5 6 7")
                         ->expected(3);
  const std::vector<CLI::Option*> zoom_opts = {
      levels_opt,
      ic->add_option("--parent", zoom.parent, "zoom: the parent run's snapshot at z = 0 (without it: write the parent's ICs)"),
      ic->add_option("--groups", zoom.groups, "zoom: the parent snapshot's friends-of-friends catalogue (fountain fof)"),
      ic->add_option("--halo", zoom.halo, "zoom: the group to zoom on (default: chosen by mass and isolation)"),
      ic->add_option("--mass-min", zoom.mass_min, "zoom: smallest M_200 of a candidate [Msun/h]")->capture_default_str(),
      ic->add_option("--mass-max", zoom.mass_max, "zoom: largest M_200 of a candidate [Msun/h]")->capture_default_str(),
      ic->add_option("--isolation", zoom.isolation, "zoom: no group of half the candidate's mass within this [Mpc/h]")
          ->capture_default_str(),
      ic->add_option("--target", zoom.target, "zoom: high-resolution particles per species wanted")->capture_default_str(),
      ic->add_option("--mass-scale", zoom.mass_scale,
                     "zoom: scale the zoom to masses x this, lengths and velocities x its cube root, energies x its "
                     "square (0.01: the paper's MFB/100)")
          ->check(CLI::PositiveNumber)
          ->capture_default_str()};

  auto* reference = app.add_subcommand("reference", "Tables of the exact solutions the validation compares with");
  reference->require_subcommand(1);
  auto* background_cmd = reference->add_subcommand(
      "background", "E(a), cosmic time, growth to second order and the leapfrog's integration factors against a");
  BackgroundTableRequest bg_request;
  background_cmd->add_option("-o,--output", bg_request.output, "Table to write")->required();
  background_cmd->add_option("--omega-m", bg_request.omega_m, "Omega_m")->capture_default_str();
  background_cmd->add_option("--omega-lambda", bg_request.omega_lambda, "Omega_Lambda (Omega_k is what makes one)")
      ->capture_default_str();
  background_cmd->add_option("--a-begin", bg_request.a_begin, "First scale factor; the factors integrate from it")
      ->capture_default_str();
  background_cmd->add_option("--a-end", bg_request.a_end, "Last scale factor")->capture_default_str();
  background_cmd->add_option("--points", bg_request.points, "Rows, equally spaced in ln a")->capture_default_str();
  auto* ewald_cmd = reference->add_subcommand(
      "ewald", "The periodic correction field of a unit mass along lines and at the published points, and the "
               "sums' convergence with their cuts");
  EwaldTableRequest ewald_request;
  ewald_cmd->add_option("-o,--output-dir", ewald_request.output_dir, "Folder for lines.txt, published.txt and convergence.txt")
      ->required();
  ewald_cmd->add_option("--points", ewald_request.points, "Random points of the convergence table")->capture_default_str();
  ewald_cmd->add_option("--line-points", ewald_request.line_points, "Samples along each line")->capture_default_str();
  ewald_cmd->add_option("--seed", ewald_request.seed, "Seed of the random points")->capture_default_str();

  auto* params_cmd = app.add_subcommand("params", "Print the parameter reference (Markdown)");

  if (is_unknown_command(argc, argv)) {
    fmt::print(stderr, "error: unknown command '{}': expected one of {} (fountain --help explains them)\n",
               argv[1], fmt::join(kCommands, ", "));
    return 2;
  }
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
      if (abandon_opt->count() > 0 && abandon_after <= 0)
        throw InputError(fmt::format("option --abandon-after-steps = {} must be a positive step count", abandon_after));
      options.abandon_after_steps = abandon_after;
      if (threads_opt->count() > 0) options.threads = threads;
      options.rank = mpi.rank();
      options.ranks = mpi.size();
      const ParameterFile params = ParameterFile::load(param_path);
      const RunSummary s = run_simulation(params, options);
      // Stopped by SIGTERM after writing a restart file: EX_TEMPFAIL, so that job scripts can
      // tell a stopped run (continue it with --restart) from a finished one.
      if (s.terminated) return 75;
      if (s.abandoned) return 0;
      if (mpi.rank() == 0)
        fmt::print(stderr, "done: {} steps to {} = {:.6g}, {} snapshots, {:.2f} s\n", s.steps, s.comoving ? "a" : "t",
                   s.final_time,
                 s.snapshots, s.wall_s);
      if (mpi.rank() == 0 && s.h_max_capped > 0)
        fmt::print(stderr, "warning: {} particle-steps were held at hydro.h_max with too few neighbours\n",
                   s.h_max_capped);
      if (mpi.rank() == 0 && s.msph_decoupled > 0)
        fmt::print(stderr, "MSPH decoupled {} force interactions\n", s.msph_decoupled);
      if (const auto& f = s.star_formation; mpi.rank() == 0 && f.mass_formed > 0.0)
        fmt::print(stderr,
                   "feedback: {:.4g} into reservoirs; {} promotions let out {:.4g}, {} dissolved particles passed "
                   "{:.4g} to their neighbours, {:.4g} still held (energy in internal units)\n",
                   f.energy_reservoir, f.promotions, f.energy_promoted, f.gas_dissolved,
                   f.energy_released - f.energy_promoted, s.reservoir_held);
      if (mpi.rank() == 0 && s.h_min_held > 0)
        fmt::print(stderr, "{} particle-steps were held at the floor of h (hydro.h_min_ratio)\n", s.h_min_held);
      if (mpi.rank() == 0 && s.ranks > 1)
        fmt::print(stderr,
                   "ranks: {}, cell owners chosen {} times; rank 0 sent {:.3g} MB in {} messages, spent {:.2f} s in "
                   "task graphs and {:.2f} s in the exchanges after them\n",
                   s.ranks, s.partitions, 1e-6 * static_cast<double>(s.bytes_sent), s.messages_sent, s.graph_s,
                   s.exchange_s);
      if (mpi.rank() == 0 && s.mesh_cells > 0)
        fmt::print(stderr, "mesh: {}^3 in {} slabs; rank 0 held {} planes, {:.3g} MB\n", s.mesh_cells, s.ranks,
                   s.mesh_planes, 1e-6 * static_cast<double>(s.mesh_bytes));
      if (mpi.rank() == 0 && s.tree_assembly.assemblies > 0) {
        const double n = static_cast<double>(s.tree_assembly.assemblies);
        fmt::print(stderr,
                   "gravity tree: assembled on each rank {} times; rank 0 received {:.4g} nodes and {:.4g} sources "
                   "a time from the other ranks\n",
                   s.tree_assembly.assemblies, static_cast<double>(s.tree_assembly.nodes_received) / n,
                   static_cast<double>(s.tree_assembly.sources_received) / n);
      }
      if (mpi.rank() == 0 && s.halo_mode)
        fmt::print(stderr, "halo mode: rank 0 kept {:.1f}% of the leaves current (mean over the recuts)\n",
                   100.0 * s.held_share);
      if (mpi.rank() == 0 && s.event_rounds.steps > 0)
        fmt::print(stderr,
                   "star formation across ranks: {} particles due to spawn or dissolve, handled in {} turns over {} steps; "
                   "{} shares of dissolved gas went to other ranks' particles\n",
                   s.event_rounds.events, s.event_rounds.turns, s.event_rounds.steps, s.event_rounds.foreign_receivers);
    } else if (*ic) {
      request.resolution_given = resolution_opt->count() > 0;
      if (request.problem != "sphere")
        for (const CLI::Option* o : sphere_opts)
          if (o->count() > 0)
            throw InputError(fmt::format("option {} applies to the sphere only, not to {}", o->get_name(),
                                         request.problem));
      if (request.problem != "cosmo" && request.problem != "zoom")
        for (const CLI::Option* o : cosmo_opts)
          if (o->count() > 0)
            throw InputError(fmt::format("option {} applies to cosmo and zoom only, not to {}", o->get_name(),
                                         request.problem));
      if (request.problem != "zoom")
        for (const CLI::Option* o : zoom_opts)
          if (o->count() > 0)
            throw InputError(fmt::format("option {} applies to zoom only, not to {}", o->get_name(), request.problem));
      if (request.problem == "zoom") {
        if (zoom_levels.size() == 3) zoom.levels = {zoom_levels[0], zoom_levels[1], zoom_levels[2]};
      }
      if (request.problem == "cosmo" || request.problem == "zoom") {
        if (gamma_opt->count() > 0)
          throw InputError("option --gamma does not apply to cosmo: comoving runs take gamma = 5/3");
        cosmo.a_start = 1.0 / (1.0 + z_start);
        cosmo.gas = !no_gas;
        cosmo.transfer = cosmology::transfer_kind_named(transfer);
      }
      if ((request.problem == "sphere" || request.problem == "evrard") && gamma_opt->count() > 0)
        throw InputError(fmt::format("option --gamma does not apply to {}: its initial conditions do not depend on "
                                     "it (the run's hydro.gamma sets it)",
                                     request.problem));
      fmt::print(stderr, "{}\n", write_ic(request));
    } else if (*fof) {
      if (fof_length->count() > 0 && fof->get_option("-b")->count() > 0)
        throw InputError("options -b and --linking-length both set the linking length: give one");
      fmt::print(stderr, "{}\n", find_groups(fof_request));
    } else if (*hop) {
      if (hop_request.peak_factor < hop_request.saddle_factor)
        throw InputError(fmt::format("option --peak-factor = {} is below --saddle-factor = {}: delta_peak must be at "
                                     "least delta_saddle",
                                     hop_request.peak_factor, hop_request.saddle_factor));
      fmt::print(stderr, "{}\n", find_hop_groups(hop_request));
    } else if (*mass_function) {
      fmt::print(stderr, "{}\n", write_mass_function(mf_request));
    } else if (*background_cmd) {
      fmt::print(stderr, "{}\n", write_background_table(bg_request));
    } else if (*ewald_cmd) {
      fmt::print(stderr, "{}\n", write_ewald_tables(ewald_request));
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
