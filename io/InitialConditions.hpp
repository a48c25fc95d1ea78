// Reading and writing gas and dark matter initial conditions in the GADGET HDF5 layout.
#pragma once
#include <string>

#include "core/Vec3.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::io {

struct InitialConditions {
  GasParticles gas;          // id, mass, x, v_full (= v), u_full (= u), h (0 where absent)
  CollisionlessParticles dm;    // id, mass, x, v_full (empty when the file has none)
  Vec3 box_size;             // /Header/BoxSize (scalar or 3-vector in the file)
  double time = 0.0;         // /Header/Time
  bool has_smoothing_length = false;
};

// Reads /Header, /PartType0 (Coordinates, Velocities, ParticleIDs, Masses or the
// MassTable[0], InternalEnergy, optional SmoothingLength) and, when NumPart_ThisFile[1] > 0,
// /PartType1 (Coordinates, Velocities, ParticleIDs, Masses or the MassTable[1]); other
// particle types are ignored. Any problem -- missing or truncated file, missing group or
// dataset, wrong shape, a count that disagrees with the header, no gas particles (dark
// matter alone is refused), NaN/inf or non-positive mass or energy, an ID used twice within
// a type or by both gas and dark matter -- throws InputError naming the file, the dataset
// and (for bad values) the particle ID.
InitialConditions read_initial_conditions(const std::string& path);

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

}  // namespace fountain::io
