// Restart files: the whole state of a run, versioned and checksummed, in portable HDF5.
#pragma once
#include <cstdint>
#include <string>

#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "starformation/StarFormationTally.hpp"

namespace fountain::io {

// 3: dark matter (/DarkMatter), gas a_grav and potential, particle counts in /Restart.
// 6: hybrid gas fields, stars among the collisionless particles, star formation tally.
inline constexpr int kRestartFormatVersion = 6;

struct RestartState {
  GasParticles gas;
  CollisionlessParticles dm;  // empty in a run without dark matter
  std::int64_t ti_current = 0;
  long long steps = 0;
  int snapshots_written = 0;
  int next_output = 1;
  double radiated_energy = 0.0;  // by cooling, since the start
  std::uint64_t next_particle_id = 0;  // the id the next spawned star takes (0: none spawned yet)
  starformation::StarFormationTally star_formation;  // since the start
  std::string parameters_yaml;  // the parameters the run was started with
};

// Writes atomically (temporary file, then rename). Every field of the gas (/Gas) and of the
// collisionless particles, dark matter and stars (/DarkMatter) is stored, with the particle counts, a format version and a
// checksum over all of it.
void write_restart(const std::string& path, const RestartState& state);

// Reads and verifies a restart file: a missing file, another format version, a field whose
// length disagrees with the stored particle count or a checksum that does not match (a
// corrupted file) throws InputError naming the file.
RestartState read_restart(const std::string& path);

}  // namespace fountain::io
