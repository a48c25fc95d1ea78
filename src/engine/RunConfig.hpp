// Everything a run is configured with, read once from the validated parameter file.
#pragma once
#include <string>
#include <vector>

#include "core/Units.hpp"
#include "cosmology/Background.hpp"
#include "cooling/CoolingParams.hpp"
#include "step/StepContext.hpp"
#include "gravity/GravityParams.hpp"
#include "hydro/HydroParams.hpp"
#include "space/Space.hpp"
#include "feedback/FeedbackParams.hpp"
#include "star_formation/StarFormationParams.hpp"

namespace fountain {

class ParameterFile;

struct OutputConfig {
  std::string directory = "output";
  std::string basename = "snapshot";
  double delta_time = 0.0;          // 0: first and last only
  std::vector<double> scale_factors;  // comoving runs: the listed output times, increasing
  bool dump_task_graph = false;
  long long dump_timeline_every = 0;
  long long statistics_every = 0;
  std::size_t gather_particles = 8192;  // across ranks: particles per message to rank 0 for its outputs
  bool fof_groups = false, hop_groups = false;  // comoving runs: catalogues beside each snapshot
};

struct RestartConfig {
  long long every_steps = 0;
  double every_minutes = 0.0;
};

// How a comoving run's initial conditions files are to be read (units h-scaled, in cgs; 0:
// what the file's /Units say, else GADGET's Mpc/h, 1e10 Msun/h and km/s).
struct ComovingFileConventions {
  double length_cgs = 0.0, mass_cgs = 0.0, velocity_cgs = 0.0;
  bool gadget_velocities = true;  // v_pec / sqrt(a); false: v_pec
  bool h_scaled = true;
};

// A comoving run (docs/physics.md §11): the clock is the scale factor from a_begin to a_end,
// the state comoving (x', v' = a^2 dx/dt, rho', u', h'). Hydro with gamma = 5/3 and gravity;
// cooling, star formation and feedback read physical values (StepContext::Expansion).
struct ComovingConfig {
  bool enabled = false;
  cosmology::CosmologyParams cosmology;
  double a_begin = 0.02;  // 0 in a parameter file: the initial conditions' /Header/Time
  double a_end = 1.0;
  ComovingFileConventions files;
};

struct RunConfig {
  double t_begin = 0.0;
  double t_end = 1.0;
  ComovingConfig comoving;
  int threads = 0;
  bool pin_threads = false;  // each task thread bound to one core (tasks/ThreadPinning.hpp)
  long long max_steps = 0;
  double smoothing_length_guess = 0.0;
  HydroParams hydro;
  GravityParams gravity;
  CoolingParams cooling;
  StarFormationParams star_formation;
  FeedbackParams feedback;  // of star formation: runs when it does
  IntegrationParams integration;
  SpaceConfig space;
  double repartition_imbalance = 0.1;  // across ranks: recut owners above this imbalance
  long long repartition_min_steps = 100;  // steps a cut stands before its imbalance is judged
  std::size_t message_bytes = std::size_t{1} << 20;  // halo mode: bytes of one all-to-all round to a rank
  bool assemble_gravity_tree = false;  // across ranks: each rank's tree from its own subtrees and others' parts
  Units units;
  OutputConfig output;
  RestartConfig restart;
  std::string parameters_yaml;      // the parameters in force, for snapshots

  // The units' values in cgs without h: `units` itself in plain runs; a comoving run's
  // h-scaled units (Mpc/h, Msun/h) divided by h (what cooling and star formation convert with).
  Units physical_units() const;
  // Across MPI ranks, whether each rank holds only its own particles and their neighbours
  // (halo mode): every run but star formation with feedback sites, whose hot-neighbour
  // searches and promotions reach particles at any distance (gravity assembles each rank's
  // tree from the others' parts, the periodic mesh is fed each rank's own particles, and star
  // formation without sites spawns and dissolves in rounds across ranks). Such a run reads
  // its gas in shares.
  bool ranks_hold_shares() const { return !star_formation.enabled || !feedback.has_sites(); }

  // Reads and cross-checks the parameters (the start time is run.t_begin, given or default).
  static RunConfig from(const ParameterFile& p);
  // The checks of times against the integer timeline, again once the start time is settled
  // (`start_origin` says where it came from): t_end after the start, dt_max and the snapshot
  // interval no shorter than one tick. Throws InputError naming the key and its line.
  void check_times(const ParameterFile& p, const std::string& start_origin) const;
  // A comoving run's t_begin and t_end: ln a_begin and ln a_end (again once a_begin is settled).
  void set_comoving_times();
};

}  // namespace fountain
