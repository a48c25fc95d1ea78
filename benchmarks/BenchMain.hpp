// Runs a whole-run benchmark's body under MPI, reporting an error with its message rather than aborting on it.
#pragma once
#include <fmt/format.h>

#include <exception>
#include <fstream>
#include <string>

#include "tasks/MpiSession.hpp"

namespace fountain::bench {

// `run(argc, argv, mpi)` is the benchmark; under mpirun the run is split across the ranks.
template <class Run>
int main_reporting_errors(int argc, char** argv, Run&& run) {
  tasks::MpiSession mpi(&argc, &argv);
  try {
    return run(argc, argv, mpi);
  } catch (const std::exception& e) {
    // Bad input (a box too small for the neighbour number, say) is reported, not aborted on.
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}

// Rank 0 prints a run's JSON line and, when a path is given, writes it there too.
inline void report_json(const tasks::MpiSession& mpi, const std::string& json, const std::string& path) {
  if (mpi.rank() != 0) return;
  fmt::print("{}", json);
  if (!path.empty()) std::ofstream(path) << json;
}

}  // namespace fountain::bench
