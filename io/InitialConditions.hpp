// Reading and writing gas and dark matter initial conditions in the GADGET HDF5 layout.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/Units.hpp"
#include "core/Vec3.hpp"
#include "cosmology/Background.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "particles/IcParticles.hpp"

namespace fountain::io {

// The units a file says it is in (HDF5 /Units, GADGET's names); 0 where it does not say.
struct IcFileUnits {
  double length_cgs = 0.0, mass_cgs = 0.0, velocity_cgs = 0.0;
};

// The cosmology a file's /Header gives (GADGET's Omega0, OmegaLambda, HubbleParam, Redshift).
struct IcFileCosmology {
  bool present = false;  // the header has all three parameters
  double omega0 = 0.0, omega_lambda = 0.0, hubble_param = 0.0, redshift = 0.0;
};

struct InitialConditions {
  GasParticles gas;          // id, mass, x, v_full (= v), u_full (= u), h (0 where absent)
  CollisionlessParticles dm;    // id, species, mass, x, v_full (empty when the file has none)
  Vec3 box_size;             // /Header/BoxSize (scalar or 3-vector in the file)
  double time = 0.0;         // /Header/Time
  bool has_smoothing_length = false;
  bool has_internal_energy = true;  // false: the file gave none (or zeros), for the run to set
  IcFileUnits units;
  IcFileCosmology cosmology;
  std::string format = "GADGET HDF5";  // or "GADGET binary format 1" / "... format 2"
  // The gas read is the file's rows [gas_first, gas_first + gas.size()) of gas_total (all of
  // them unless IcReadOptions asked for a share), and the collisionless particles likewise of
  // all the file's collisionless types in the order `dm` lists them (types 1, 2, 3, 5).
  std::size_t gas_first = 0, gas_total = 0;
  std::size_t dm_first = 0, dm_total = 0;
};

struct IcReadOptions {
  // A cosmological run's initial conditions: dark matter alone is allowed, a gas particle's
  // internal energy may be missing or 0 (the run sets it), and the low-resolution dark matter
  // of types 2, 3 and 5 is read (as Species::LowResDarkMatter, masses per particle).
  bool cosmological = false;
  // A share for one of share_ranks MPI ranks that each hold their own (runs without star
  // formation): the file's gas rows [n r / R, n (r + 1) / R) for r = share_rank, R =
  // share_ranks, and the same rows of its collisionless particles (of all their types laid end
  // to end), read by hyperslab from HDF5 (a GADGET binary file is read whole and cut). Every
  // check of the values still holds per particle; that no ID repeats, within a type or across
  // them, is checked by share_rank 0 alone, which reads every ID for it. A cosmological share's
  // has_internal_energy speaks for its rows only: the ranks must compare theirs.
  int share_rank = 0, share_ranks = 1;
};

// Reads GADGET-layout HDF5 or GADGET binary (format 1 or 2, one file or path.0 .. path.(n-1),
// detected from the first bytes), with no conversion of units or conventions. HDF5: reads /Header, /PartType0 (Coordinates, Velocities, ParticleIDs, Masses or the
// MassTable[0], InternalEnergy, optional SmoothingLength) and, when NumPart_ThisFile[1] > 0,
// /PartType1 (Coordinates, Velocities, ParticleIDs, Masses or the MassTable[1]); other
// particle types are ignored. Any problem -- missing or truncated file, missing group or
// dataset, wrong shape, a count that disagrees with the header, no gas particles (dark
// matter alone is refused), NaN/inf or non-positive mass or energy, an ID used twice within
// a type or by both gas and dark matter -- throws InputError naming the file, the dataset
// and (for bad values) the particle ID.
InitialConditions read_initial_conditions(const std::string& path, const IcReadOptions& options = {});

// Writes gas initial conditions in the same layout (used by `fountain ic`).
void write_initial_conditions(const std::string& path, const GasParticles& gas, const Vec3& box_size,
                              bool periodic, double time = 0.0);

// Writes gas and dark matter: the gas as above, the dark matter as /PartType1 (Coordinates,
// Velocities, ParticleIDs, Masses); /Header NumPart_ThisFile and NumPart_Total count both
// types, and MassTable holds each type's particle mass where all its particles share one
// (0 otherwise; the Masses datasets are written either way). IDs must be unique across both
// types. read_initial_conditions reads both back.
void write_initial_conditions(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                              const Vec3& box_size, bool periodic, double time = 0.0);

// A comoving run's initial conditions at scale factor a, from particles in its code variables
// (h-scaled units `units`): written as GADGET's cosmological files are (Time = a, the
// cosmology in /Header, /Units, velocities v_pec / sqrt(a) = v' / a^(3/2), physical internal
// energies u = u' / a^2), which a comoving run reads back exactly. Gas may be absent.
struct CosmologicalIcInfo {
  cosmology::CosmologyParams cosmology;
  double a = 1.0;
  Units units;
  // How a generator made the field (seed, spectrum, order, pairing), written as attributes of
  // /Cosmology, so that a file says which realisation it holds.
  std::vector<std::pair<std::string, double>> generator_numbers;
  std::vector<std::pair<std::string, std::int64_t>> generator_integers;
  std::vector<std::pair<std::string, std::string>> generator_words;
};
void write_initial_conditions(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                              double box_size, const CosmologicalIcInfo& info);
// The same from a generator's lean stores (v and u in the run's variables). Nothing is copied
// whole: fields are written where they lie, scaled ones a piece at a time.
void write_initial_conditions(const std::string& path, const IcGasParticles& gas, const IcCollisionlessParticles& dm,
                              double box_size, const CosmologicalIcInfo& info);

}  // namespace fountain::io
