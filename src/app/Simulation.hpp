// A whole run: reads the initial conditions, steps the engine, writes snapshots and dumps.
#pragma once
#include <cstdint>
#include <string>

#include "engine/RunConfig.hpp"

namespace fountain {

class ParameterFile;

struct RunSummary {
  long long steps = 0;
  int snapshots = 0;
  double wall_s = 0.0;
  double final_time = 0.0;
  bool terminated = false;  // stopped by SIGTERM after writing a restart file
  bool abandoned = false;   // stopped at the step asked for, as a killed run would (nothing more written)
  // Across MPI ranks (1 when alone): how often cell owners were chosen, and what this rank sent.
  int ranks = 1;
  int partitions = 0;
  std::uint64_t bytes_sent = 0, messages_sent = 0;
  double graph_s = 0.0, exchange_s = 0.0;  // this rank: in task graphs, in the exchanges after them
  bool halo_mode = false;
  double held_share = 1.0;  // of the leaves, kept current by this rank (Engine::held_share)
};

// Runs the parameter file's problem to run.t_end, or continues it from its restart file
// (<output.directory>/restart.hdf5) with `restart`. Problems with the input (the parameter
// file, the IC file, the output folder, the restart file) throw InputError before any step.
// With abandon_after_steps > 0 the run stops once that many steps are done and writes
// nothing more, as a run killed there would: tests of restarts stop a run deterministically.
RunSummary run_simulation(const ParameterFile& params, bool quiet = false, int threads_override = -1,
                          bool restart = false, long long abandon_after_steps = 0);

// Where a run's restart file lives.
std::string restart_path(const ParameterFile& params);

// The build's identity, recorded in every snapshot.
std::string git_revision();
std::string build_options();

}  // namespace fountain
