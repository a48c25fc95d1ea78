// A whole run: reads the initial conditions, steps the engine, writes snapshots and dumps.
#pragma once
#include <string>

#include "engine/RunConfig.hpp"

namespace fountain {

class ParameterFile;

struct RunSummary {
  long long steps = 0;
  int snapshots = 0;
  double wall_s = 0.0;
  double final_time = 0.0;
};

// Runs the parameter file's problem to run.t_end. Problems with the input (the parameter
// file, the IC file, the output folder) throw InputError before any step is taken.
RunSummary run_simulation(const ParameterFile& params, bool quiet = false, int threads_override = -1);

// The build's identity, recorded in every snapshot.
std::string git_revision();
std::string build_options();

}  // namespace fountain
