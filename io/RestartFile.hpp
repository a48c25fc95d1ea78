// Restart files: the whole state of a run, versioned and checksummed, in portable HDF5.
#pragma once
#include <cstdint>
#include <string>

#include "particles/GasParticles.hpp"

namespace fountain::io {

inline constexpr int kRestartFormatVersion = 2;

struct RestartState {
  GasParticles gas;
  std::int64_t ti_current = 0;
  long long steps = 0;
  int snapshots_written = 0;
  int next_output = 1;
  std::string parameters_yaml;  // the parameters the run was started with
};

// Writes atomically (temporary file, then rename). Every particle field is stored, plus a
// format version and a checksum over all of it.
void write_restart(const std::string& path, const RestartState& state);

// Reads and verifies a restart file: a missing file, another format version or a checksum
// that does not match (a corrupted file) throws InputError naming the file.
RestartState read_restart(const std::string& path);

}  // namespace fountain::io
