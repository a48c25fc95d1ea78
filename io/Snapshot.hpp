// HDF5 snapshots in the GADGET/SWIFT layout, with units, the parameters used and the git revision.
#pragma once
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "core/Units.hpp"
#include "core/Vec3.hpp"
#include "cosmology/Background.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/FieldInfo.hpp"
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
  // A comoving run's: `time` is then the scale factor a, the particles hold comoving code
  // variables, and the file is written as GADGET's cosmological snapshots are (velocities
  // v_pec / sqrt(a), physical internal energies, the cosmology in /Header and /Cosmology).
  std::optional<cosmology::CosmologyParams> cosmology;
};

// The datasets of each PartType group are the fields the table of particle fields
// (particles/ParticleFields.hpp) flags for snapshots, under the table's names and with its
// units and descriptions, followed by the gas datasets below, worked out from the fields when
// the snapshot is written (not stored).
struct ComputedDataset {
  const char* name;
  Dimensions units;
  const char* description;
};
// Pressure's description gains the run's gamma.
inline constexpr ComputedDataset kPressureDataset{
    "Pressure", {.mass = 1, .length = -1, .time = -2, .a_gamma = -3}, "Pressures of the particles, (gamma - 1) rho u"};
// Written when SnapshotInfo::temperature is set (by every run).
inline constexpr ComputedDataset kTemperatureDataset{
    "Temperature", {}, "Temperatures of the particles in K, with the cooling tables' mean particle mass"};

// SWIFT's "Expression for physical CGS units" of a dataset: "U_M U_L^-3", or "[ - ]".
std::string unit_expression(const Dimensions& d);

// Writes `path` (to a temporary name first, renamed on success, so a full disk never
// leaves a half-written snapshot under the final name). Throws InputError naming the path
// when the folder is not writable or a write fails.
void write_snapshot(const std::string& path, const GasParticles& gas, const SnapshotInfo& info);

// The same with the collisionless particles: when `dm` holds dark matter it is written as
// /PartType1, stars as /PartType4, each counted in /Header (MassTable = 0: the masses are per
// particle).
void write_snapshot(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                    const SnapshotInfo& info);

// Particles per snapshot group: gas (/PartType0), dark matter (1), lower-resolution dark
// matter (2), stars (4).
struct SnapshotCounts {
  std::size_t gas = 0, dark_matter = 0, low_res = 0, stars = 0;
};

// A snapshot written as its particles arrive, in the file's order, a run at a time: across
// MPI ranks rank 0 writes what each leaf's owner sends, so that no rank ever holds every
// particle. The file is the one write_snapshot writes of the same particles. Under a
// temporary name until close(), which checks that every particle came; failures throw as
// write_snapshot's do, and a writer destroyed before close() leaves no file.
class SnapshotWriter {
 public:
  SnapshotWriter(const std::string& path, const SnapshotInfo& info, const SnapshotCounts& counts);
  ~SnapshotWriter();
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;
  // The next gas particles: gas[first .. first + count).
  void add_gas(const GasParticles& gas, std::size_t first, std::size_t count);
  // The next collisionless particles, each to its species' group.
  void add_collisionless(const CollisionlessParticles& p, std::size_t first, std::size_t count);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fountain::io
