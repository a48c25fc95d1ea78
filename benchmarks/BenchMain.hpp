// Runs a whole-run benchmark's body under MPI, reporting an error with its message rather than aborting on it.
#pragma once
#include <fmt/format.h>

#include <exception>

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

}  // namespace fountain::bench
