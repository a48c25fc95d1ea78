// A run's set-up: its parameters, the output folder held, the initial conditions read and checked, a restart file's state.
#pragma once
#include <memory>
#include <optional>

#include "app/OutputFolder.hpp"
#include "app/Simulation.hpp"
#include "engine/Engine.hpp"
#include "io/InitialConditions.hpp"
#include "io/RestartFile.hpp"

namespace fountain {

// Everything a run needs before its engine exists.
struct RunStart {
  RunConfig config;
  io::InitialConditions ic;       // the restart file's particles in place of the IC's on a restart
  io::RestartState restart;       // a restart's state beyond its particles (empty on a fresh run)
  std::optional<Engine::GasShare> share;  // the gas in `ic` is this rank's share of the file's
  std::unique_ptr<OutputFolderLock> lock;  // rank 0's, held for the whole run
};

// Reads and checks everything a run starts from, before any step: problems with the input
// (the parameter file, the IC file, the output folder and what it holds, the restart file)
// throw InputError naming the file and key.
RunStart prepare_run(const ParameterFile& params, const RunOptions& options);

// The engine's first forces (a fresh run) or the restart file's state put back (a restart).
void start_engine(Engine& engine, const RunStart& start, const ParameterFile& params, const RunOptions& options,
                  bool quiet);

}  // namespace fountain
