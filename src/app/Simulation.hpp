// A whole run: reads the initial conditions, steps the engine, writes snapshots and dumps.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "engine/Engine.hpp"
#include "engine/RunConfig.hpp"
#include "step/StarFormationTally.hpp"

namespace fountain {

class ParameterFile;

struct RunSummary {
  long long steps = 0;
  int snapshots = 0;
  double wall_s = 0.0;
  double final_time = 0.0;
  bool comoving = false;  // final_time is then the scale factor
  bool terminated = false;  // stopped by SIGTERM after writing a restart file
  bool abandoned = false;   // stopped at the step asked for, as a killed run would (nothing more written)
  // Across MPI ranks (1 when alone): how often cell owners were chosen, and what this rank sent.
  int ranks = 1;
  int partitions = 0;
  std::uint64_t bytes_sent = 0, messages_sent = 0;
  double graph_s = 0.0, exchange_s = 0.0;  // this rank: in task graphs, in the exchanges after them
  bool halo_mode = false;
  double held_share = 1.0;  // of the leaves, kept current by this rank (Engine::held_share)
  int mesh_cells = 0, mesh_planes = 0;  // the periodic mesh's side, and this rank's x-planes of it
  std::size_t mesh_bytes = 0;           // of the mesh, held by this rank
  Engine::TreeAssembly tree_assembly;   // the gravity trees this rank assembled across ranks
  Engine::EventRounds event_rounds;     // star formation's spawning and dissolving across ranks
  long long h_max_capped = 0;  // particle-steps held at hydro.h_max short of neighbours
  long long h_min_held = 0;    // particle-steps held at the floor of h (hydro.h_min_ratio)
  long long msph_decoupled = 0;  // force interactions the MSPH rule dropped
  star_formation::StarFormationTally star_formation;  // since the start (runs with star formation)
  double reservoir_held = 0.0;  // feedback energy still in reservoirs at the end
};

// How `fountain run` was asked to run, beyond the parameter file.
struct RunOptions {
  bool quiet = false;
  std::optional<long long> threads;  // -t: overrides run.threads (checked against its range)
  bool restart = false;              // continue from <output.directory>/restart.hdf5
  bool overwrite = false;            // a fresh run may replace an earlier run's files in its folder
  // With a value > 0 the run stops once that many steps are done and writes nothing more, as
  // a run killed there would: tests of restarts stop a run deterministically.
  long long abandon_after_steps = 0;
  int rank = 0;  // this process's MPI rank: rank 0 alone holds the output folder's lock
  int ranks = 1;  // the run's MPI ranks
};

// Runs the parameter file's problem to run.t_end, or continues it from its restart file
// (<output.directory>/restart.hdf5) with `options.restart`. Problems with the input (the
// parameter file, the IC file, the output folder and what it holds, the restart file) throw
// InputError before any step. The run holds its output folder's lock until it returns.
RunSummary run_simulation(const ParameterFile& params, const RunOptions& options = {});

// Where a run's restart file lives.
std::string restart_path(const ParameterFile& params);

// The build's identity, recorded in every snapshot.
std::string git_revision();
std::string build_options();

}  // namespace fountain
