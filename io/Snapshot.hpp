// HDF5 snapshots in the GADGET/SWIFT layout, with units, the parameters used and the git revision.
#pragma once
#include <functional>
#include <string>

#include "core/Units.hpp"
#include "core/Vec3.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::io {

struct SnapshotInfo {
  double time = 0.0;
  long long step = 0;
  Vec3 box_size;
  bool periodic = false;
  Units units;
  double gamma = 5.0 / 3.0;
  std::string parameters_yaml;  // every parameter in force
  std::string git_revision;
  std::string build_options;
  // Temperature (K) of gas of specific energy u; when set, gas gets a Temperature dataset.
  std::function<double(double)> temperature;
  bool star_formation = false;  // write the hybrid gas fields (hidden stars, reservoir, promotion)
};

// Writes `path` (to a temporary name first, renamed on success, so a full disk never
// leaves a half-written snapshot under the final name). Throws InputError naming the path
// when the folder is not writable or a write fails.
void write_snapshot(const std::string& path, const GasParticles& gas, const SnapshotInfo& info);

// The same with dark matter: when `dm` is not empty it is written as /PartType1
// (Coordinates, Velocities = v_full, Masses, ParticleIDs, Potential, Acceleration) and
// counted in /Header (MassTable[1] = 0: the masses are per particle).
void write_snapshot(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                    const SnapshotInfo& info);

}  // namespace fountain::io
