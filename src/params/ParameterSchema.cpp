#include "params/ParameterSchema.hpp"

#include <fmt/format.h>

namespace fountain {

namespace {
constexpr double inf = std::numeric_limits<double>::infinity();

ParamSpec spec(std::string key, ParamKind kind, std::optional<std::string> def, double lo, double hi,
               bool lo_exclusive, std::string doc, std::vector<std::string> choices = {}) {
  ParamSpec p;
  p.key = std::move(key);
  p.kind = kind;
  p.default_value = std::move(def);
  p.min = lo;
  p.max = hi;
  p.min_exclusive = lo_exclusive;
  p.doc = std::move(doc);
  p.choices = std::move(choices);
  return p;
}
ParamSpec real(std::string key, std::optional<std::string> def, double lo, double hi,
               std::string doc, bool lo_exclusive = false) {
  return spec(std::move(key), ParamKind::Real, std::move(def), lo, hi, lo_exclusive, std::move(doc));
}
ParamSpec integer(std::string key, std::optional<std::string> def, double lo, double hi,
                  std::string doc) {
  return spec(std::move(key), ParamKind::Integer, std::move(def), lo, hi, false, std::move(doc));
}
ParamSpec boolean(std::string key, std::string def, std::string doc) {
  return spec(std::move(key), ParamKind::Boolean, std::move(def), -inf, inf, false, std::move(doc));
}
ParamSpec text(std::string key, std::optional<std::string> def, std::string doc,
               std::vector<std::string> choices = {}) {
  return spec(std::move(key), ParamKind::Text, std::move(def), -inf, inf, false, std::move(doc), std::move(choices));
}
ParamSpec real_list(std::string key, double lo, double hi, std::string doc, bool lo_exclusive = false) {
  return spec(std::move(key), ParamKind::RealList, std::string(), lo, hi, lo_exclusive, std::move(doc));
}
ParamSpec choice_or_number(std::string key, std::string def, std::vector<std::string> choices, double lo, double hi,
                           std::string doc) {
  ParamSpec p = spec(std::move(key), ParamKind::Text, std::move(def), lo, hi, false, std::move(doc), std::move(choices));
  p.or_number = true;
  return p;
}
// A required key that `flag`, when true, makes unnecessary; it then takes `fallback`.
ParamSpec required_unless(ParamSpec p, std::string flag, std::string fallback) {
  p.required_unless = std::move(flag);
  p.default_unless = std::move(fallback);
  return p;
}
}  // namespace

const std::vector<ParamSpec>& parameter_schema() {
  static const std::vector<ParamSpec> schema = {
      // run
      real("run.t_begin", "0", -inf, inf, "Simulation time of the initial conditions (internal units)."),
      required_unless(real("run.t_end", std::nullopt, -inf, inf,
                           "Time at which the run stops (internal units). Required, but in a comoving run, which "
                           "ends at cosmology.a_end."),
                      "cosmology.enabled", "0"),
      integer("run.threads", "0", 0, 4096, "Worker threads; 0 uses every core TBB sees."),
      boolean("run.pin_threads", "false",
              "Bind each worker thread to one core (each MPI rank on a node to its own cores); "
              "off, threads float between cores."),
      integer("run.max_steps", "0", 0, 1e15, "Stop after this many steps; 0 means no limit."),
      // initial conditions
      text("initial_conditions.file", std::nullopt,
           "GADGET-layout HDF5 initial conditions; a relative path is taken from the parameter file's folder. Required."),
      boolean("initial_conditions.periodic", "false",
              "Periodic box of size /Header/BoxSize (true) or open boundaries (false)."),
      real("initial_conditions.length_unit_cgs", "0", 0, inf,
           "Comoving runs: the files' length unit in cm, h-scaled (3.0856775814913673e24 for Mpc/h, 3.0856775814913673e21 for N-GenIC's kpc/h); 0 takes an HDF5 file's /Units (UnitLength_in_cm) and otherwise Mpc/h."),
      real("initial_conditions.mass_unit_cgs", "0", 0, inf,
           "Comoving runs: the files' mass unit in g, h-scaled; 0 takes an HDF5 file's /Units (UnitMass_in_g) and otherwise 1e10 Msun/h (GADGET's, MUSIC's and N-GenIC's)."),
      real("initial_conditions.velocity_unit_cgs", "0", 0, inf,
           "Comoving runs: the files' velocity unit in cm/s; 0 takes an HDF5 file's /Units (UnitVelocity_in_cm_per_s) and otherwise km/s."),
      text("initial_conditions.velocity_convention", "gadget",
           "Comoving runs: what the files' velocities are. gadget: v_pec / sqrt(a), as N-GenIC, 2LPTic, MUSIC, monofonIC and Fountain's own snapshots write them; peculiar: v_pec = a dx/dt.",
           {"gadget", "peculiar"}),
      boolean("initial_conditions.h_scaled", "true",
              "Comoving runs: the files' lengths and masses are in h-scaled units (Mpc/h, Msun/h); false multiplies them by h on reading."),
      real("initial_conditions.smoothing_length_guess", "0", 0, inf,
           "First guess of h where the file has no SmoothingLength; 0 estimates it from the mean interparticle spacing."),
      // output
      text("output.directory", "output", "Folder for snapshots, task dumps and the log; created if missing; relative to the working directory."),
      text("output.basename", "snapshot", "Snapshot files are <basename>_NNNN.hdf5."),
      real("output.delta_time", "0", 0, inf,
           "Time between snapshots; 0 writes only the first and the last. Not for comoving runs, which list their output times."),
      real_list("output.scale_factors", 0, inf,
                "Comoving runs: scale factors of the snapshots between the first and the last, in increasing order, as a YAML list or comma-separated.",
                true),
      real_list("output.redshifts", -1, inf,
                "Comoving runs: redshifts of the snapshots between the first and the last, in decreasing order (may be given with output.scale_factors: the union is written).",
                true),
      boolean("output.dump_task_graph", "false",
              "Write the task dependency graph (DOT and SWIFT-style CSV) after the first step."),
      integer("output.dump_timeline_every", "0", 0, 1e15,
              "Write a per-task timeline (CSV) every this many steps; 0 never."),
      integer("output.statistics_every", "0", 0, 1e15,
              "Append a line of global diagnostics (gas phases, energies, momenta, unbound gas) to <output.directory>/statistics.txt every this many steps; 0 never. Comoving runs: physical values, the time column a."),
      integer("output.gather_particles", "8192", 1, 1e15,
              "Across MPI ranks: snapshots are written by rank 0 from the particles each rank sends it, at most this many per message, so that rank 0 never holds more than that many beside its own."),
      boolean("output.fof_groups", "false",
              "Comoving runs: find each snapshot's friends-of-friends halos as it is written (fountain fof's defaults), into <output.directory>/fof_NNNN.hdf5."),
      boolean("output.hop_groups", "false",
              "Comoving runs: find each snapshot's HOP groups of the baryons as it is written (fountain hop's defaults), into <output.directory>/hop_NNNN.hdf5."),
      // restart
      integer("restart.every_steps", "0", 0, 1e15,
              "A restart file <output.directory>/restart.hdf5 falls due every this many steps; it is written at the next recut of the cells after that (a few to a few tens of steps later, so writing it changes nothing in the run; if none comes within 1000 steps the cells are recut for it). The first is written at the start. 0: never (SIGTERM always writes one)."),
      real("restart.every_minutes", "0", 0, inf, "A restart file also falls due when this many minutes of wall time have passed since the last (written as for every_steps); 0 never."),
      // cosmology
      boolean("cosmology.enabled", "false",
              "Comoving integration in an expanding periodic box (docs/physics.md, section 11): the clock is the scale factor a, positions and velocities comoving, units h-scaled (units.length_cgs is per h, so Mpc/h by default; likewise the mass unit). Needs gravity, a periodic box and gamma = 5/3."),
      real("cosmology.omega_m", "0.3", 0, inf, "Omega_m: matter density today in units of the critical density.", true),
      real("cosmology.omega_lambda", "0.7", -inf, inf, "Omega_Lambda: the cosmological constant's (w = -1). Omega_m + Omega_Lambda != 1 gives curvature."),
      real("cosmology.omega_b", "0.04", 0, inf, "Omega_b: baryons' (sets the gas's mean density in the RMS-displacement step limit); at most omega_m."),
      real("cosmology.hubble_param", "0.7", 0, inf, "h = H0 / (100 km/s/Mpc): converts h-scaled units to physical ones.", true),
      real("cosmology.a_begin", "0", 0, 1,
           "Scale factor at the start; 0 takes the initial conditions' /Header/Time. When given, the file's Time must agree to 1e-6."),
      real("cosmology.a_end", "1", 0, inf, "Scale factor at which the run stops.", true),
      // units
      real("units.length_cgs", "3.0856775814913673e24", 0, inf, "Internal length unit in cm (default Mpc).", true),
      real("units.mass_cgs", "1.988409870698051e33", 0, inf, "Internal mass unit in g (default Msun).", true),
      real("units.velocity_cgs", "1e5", 0, inf, "Internal velocity unit in cm/s (default km/s).", true),
      // hydro
      real("hydro.gamma", "1.6666666666666667", 1, 3, "Adiabatic index.", true),
      real("hydro.neighbours", "32", 12, 1e4, "Target kernel-weighted neighbour number N_ngb."),
      real("hydro.neighbours_tolerance", "1", 0, 1e4,
           "Accepted deviation of the weighted neighbour number from N_ngb.", true),
      real("hydro.sph_alpha", "1.5", 0, 2, "Power alpha of the momentum equation (the paper: 3/2)."),
      real("hydro.viscosity_alpha", "1.3", 0, 10, "Artificial-viscosity alpha_v."),
      boolean("hydro.viscosity_reconstruction", "false",
              "The viscosity sees each pair's velocities carried to the pair's midpoint along their (linearly exact) "
              "gradients with a van Leer slope limiter: no viscosity where the flow is smooth, all of it in shocks. "
              "false: the paper's viscosity, acting on every approaching pair."),
      real("hydro.courant", "0.1", 0, 1, "Courant factor alpha_c.", true),
      boolean("hydro.msph", "true", "Multiphase SPH neighbour rule (paper eqs 4-6); false gives standard SPH."),
      real("hydro.msph_A", "10", 1, inf, "Density-contrast threshold A of the MSPH rule."),
      real("hydro.msph_A_prime", "10", 1, inf, "Energy-contrast threshold A' of the MSPH rule."),
      real("hydro.h_max", "0", 0, inf, "Largest smoothing length allowed; 0 means no limit."),
      real("hydro.h_min_ratio", "0", 0, inf,
           "Smallest smoothing length as a multiple of the gas's spline softening length 2.8 eps_gas (GADGET's "
           "MinGasHsmlFractional); a particle that would need less keeps this h and more neighbours. 0: no floor."),
      integer("hydro.max_h_iterations", "50", 1, 1000, "Iterations of the smoothing-length solver before the run stops with an error."),
      // gravity
      boolean("gravity.enabled", "false",
              "Self-gravity of all particles: a tree with open boundaries, or in a periodic box (initial_conditions.periodic) TreePM, a mesh for the long range and the tree for the short range."),
      integer("gravity.mesh_cells", "0", 0, 4096,
              "Periodic boxes: cells per side of the long-range mesh (even, at least 16); 0 takes the smallest power of two at least the particles per side (GADGET's PMGRID choice)."),
      real("gravity.split_cells", "1.25", 0.5, 8,
           "Periodic boxes: the TreePM split scale r_s in mesh cells (GADGET's ASMTH); the tree's short range is cut off at 4.5 r_s."),
      real("gravity.G", "0", 0, inf, "Newton's constant in internal units; 0 derives it from the unit system."),
      real("gravity.softening_dark_matter", "0", 0, inf,
           "Plummer-equivalent softening of dark matter (the spline reaches 2.8 times it); stars take the mean of gas and dark matter."),
      real("gravity.softening_gas", "0", 0, inf, "Plummer-equivalent softening of gas; 0 takes half the dark matter's (the paper)."),
      real("gravity.softening_max_physical", "0", 0, inf,
           "Comoving runs: the dark matter's largest physical softening (GADGET's SofteningMaxPhys). The softenings above are comoving; once a times softening_dark_matter exceeds this, every softening shrinks in proportion so that the dark matter's stays at this physical length. A zoom's low-resolution particles soften over softening_dark_matter times the cube root of their mass over the high-resolution dark matter's. 0: comoving throughout."),
      real("gravity.alpha_force", "0.01", 0, 1, "Relative tree opening criterion: accept a node when its neglected term is below alpha_force |a_old|.", true),
      text("gravity.opening_criterion", "gadget2", "gadget2: G M l^2/r^4 <= alpha |a_old| (GADGET, the paper); quadrupole: G M l^3/r^5 (GADGET-4, matched to the quadrupole expansion).",
           {"gadget2", "quadrupole"}),
      real("gravity.eta", "0.08", 0, 10, "Gravitational timestep dt = sqrt(2 eta eps / |a|).", true),
      // cooling
      boolean("cooling.enabled", "false", "Optically thin radiative cooling from the Sutherland & Dopita (1993) CIE tables, implicit per particle."),
      choice_or_number("cooling.metallicity", "primordial", {"primordial"}, -3, 0.5,
                       "Gas metallicity: 'primordial' or [Fe/H] between -3 and 0.5 (the paper tracks no enrichment)."),
      text("cooling.table_directory", "", "Folder of the SD93 .cie tables; empty uses the copy shipped in data/cooling/sutherland_dopita_1993."),
      real("cooling.hydrogen_fraction", "0.76", 0, 1, "Hydrogen mass fraction X (n_H = X rho / m_p).", true),
      // star formation
      boolean("star_formation.enabled", "false", "Star formation (paper section 2.2): eligible gas turns into hidden stellar mass, then star particles."),
      real("star_formation.efficiency", "0.1", 0, 1, "c*: the rate is c* M_gas / t_dyn, t_dyn = 1/sqrt(4 pi G rho)."),
      real("star_formation.density_threshold_cgs", "5e-26", 0, inf, "rho*: gas forms stars only above this physical density (g cm^-3)."),
      real("star_formation.temperature_threshold", "4e4", 0, inf, "T* (K): gas forms stars only below it; feedback's cold phase is T < 2 T*.", true),
      real("star_formation.spawn_fraction", "0.3", 0, 1, "A star particle is spawned when the hidden stellar mass reaches this fraction of the initial gas mass.", true),
      real("star_formation.dissolve_fraction", "0.1", 0, 1, "A gas particle whose mass falls to this fraction of its initial mass is shared among its gas neighbours.", true),
      // feedback
      real("feedback.energy_per_solar_mass", "4e48", 0, inf, "e_sn: supernova energy (erg) per solar mass of stars formed, injected at formation."),
      real("feedback.eps_cold", "0", 0, 1, "eps_c: fraction of e_sn kept in the star-forming particle's reservoir until it can be promoted to the hot phase."),
      real("feedback.eps_hot", "0", 0, 1, "eps_h: fraction of e_sn given as thermal energy to the nearest hot neighbours, in proportion to mass."),
      integer("feedback.hot_neighbours", "10", 1, 1000, "How many nearest hot neighbours receive eps_h and set the promotion threshold."),
      real("feedback.max_search_radius", "0", 0, inf, "Largest distance (internal length) searched for hot neighbours; 0: no limit."),
      real("feedback.promotion_factor", "50", 1, inf, "Promotion threshold T_prom is this times T*, unless the hot neighbours' mean temperature is higher."),
      real("feedback.promotion_hot_factor", "2", 0, inf, "When the hot neighbours' mean temperature exceeds promotion_factor x T*, T_prom is this times that mean."),
      // time integration
      real("time_integration.dt_min", "1e-8", 0, inf, "Smallest timestep allowed; a particle that needs less stops the run.", true),
      real("time_integration.dt_max", "1e-6", 0, inf, "Largest timestep (in a comoving run, of physical time).", true),
      real("time_integration.max_dln_a", "0.01", 0, 1,
           "Comoving runs: largest step in ln a (GADGET's MaxSizeTimestep).", true),
      text("time_integration.courant_criterion", "syw",
           "syw: the paper's Courant criterion, dt = alpha_c h / (h |div v| + max(c, |v|) (1 + 0.6 alpha_v)); "
           "signal_velocity: GADGET-2's and SWIFT's, dt = C h / v_sig,max with v_sig,ij = c_i + c_j - 3 min(0, "
           "v_ij.r_ij / r_ij) over the force loop's pairs and C = 2 alpha_c / (1 + 0.6 alpha_v), so that both give "
           "the same step to gas at rest (alpha_c: hydro.courant).",
           {"syw", "signal_velocity"}),
      boolean("time_integration.timestep_limiter", "true",
              "Keep every particle's step within a factor of its neighbours' and wake sleeping neighbours of short-step particles (beyond the paper; false for paper-faithful runs)."),
      integer("time_integration.limiter_bin_difference", "2", 1, 10,
              "Largest difference of time bins between neighbours under the limiter: 2 allows steps 4x a neighbour's, 1 allows 2x."),
      // space
      integer("space.cell_split_size", "256", 8, 1e6, "Octree cells with more particles than this are split."),
      integer("space.top_cells", "0", 0, 128, "Top-level cells along the longest box side; 0 chooses from the particle number. At most one top cell per particle (or 64 in all) is allowed."),
      choice_or_number("space.rebuild_skin", "auto", {"auto"}, 0.01, 10,
                       "Cells cover (1 + skin) times their largest h; the graph is rebuilt when h growth plus motion use up the skin. 'auto': 0.25, or 0.5 in a comoving run (whose rebuilds follow the motion, not h)."),
      // domain decomposition (MPI)
      real("domain.repartition_imbalance", "0.1", 0, inf,
           "Across MPI ranks: when the cells are recut, their owners are chosen anew if, in the work measured since they were last chosen, the most loaded rank's exceeds the mean by more than this fraction (0: at every recut that domain.repartition_min_steps allows)."),
      integer("domain.repartition_min_steps", "100", 0, 1e15,
              "Across MPI ranks: owners, once chosen, are judged only after this many steps (0: at every recut), so that the imbalance is measured over enough steps to be more than noise."),
      boolean("domain.assemble_gravity_tree", "false",
              "Across MPI ranks, with gravity: each rank builds the tree of its own cells' particles and, each step, receives from the other ranks what of their trees its walks open, where otherwise every rank builds the whole tree from every particle. The results are the same bits; while every rank holds every particle the whole tree costs less time and traffic (docs/performance.md)."),
      integer("domain.message_bytes", "1048576", 1, 1e15,
              "Across MPI ranks, in halo mode: the most bytes one round of an all-to-all carries from a rank to another (a recut's particles; the exchange after each task graph, in whole cells), and about the most a rank receives in one round of the periodic mesh's particle exchange (whole planes); a larger exchange goes in several rounds, so that the buffers kept for them stay about this size."),
  };
  return schema;
}

std::string parameter_reference_markdown() {
  std::string out =
      "# Parameter reference\n\n"
      "Generated from `src/params/ParameterSchema.cpp` by `fountain params`; a test keeps this file\n"
      "identical to that output. A parameter file is YAML with one mapping per section. Unknown\n"
      "keys, values of the wrong type, values out of range and missing required keys stop the run\n"
      "before any work, with a message naming the key and the file.\n";
  std::string section;
  for (const auto& p : parameter_schema()) {
    const auto dot = p.key.find('.');
    const std::string sec = p.key.substr(0, dot);
    if (sec != section) {
      section = sec;
      out += fmt::format("\n## `{}`\n\n| key | type | default | range | meaning |\n|---|---|---|---|---|\n", sec);
    }
    const char* kind = p.kind == ParamKind::Real      ? "real"
                       : p.kind == ParamKind::Integer ? "integer"
                       : p.kind == ParamKind::Boolean ? "boolean"
                       : p.kind == ParamKind::RealList ? "list of reals"
                                                      : "text";
    std::string range;
    if (p.kind == ParamKind::Real || p.kind == ParamKind::Integer || p.kind == ParamKind::RealList) {
      const bool has_lo = p.min != -inf, has_hi = p.max != inf;
      if (has_lo || has_hi)
        range = fmt::format("{}{}, {}]", p.min_exclusive ? "(" : "[", has_lo ? fmt::format("{:g}", p.min) : "-inf",
                            has_hi ? fmt::format("{:g}", p.max) : "inf");
    } else if (!p.choices.empty()) {
      for (const auto& c : p.choices) range += (range.empty() ? "" : ", ") + c;
      if (p.or_number) range += fmt::format(", or [{:g}, {:g}]", p.min, p.max);
    }
    out += fmt::format("| `{}` | {} | {} | {} | {} |\n", p.key.substr(dot + 1), kind,
                       p.default_value ? (p.default_value->empty() ? "(none)" : "`" + *p.default_value + "`")
                       : p.required_unless.empty() ? "**required**"
                                                   : fmt::format("**required** unless `{}`", p.required_unless),
                       range, p.doc);
  }
  return out;
}

}  // namespace fountain
