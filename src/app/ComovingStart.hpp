// A comoving run's initial conditions put into code variables: its start, units and GADGET's conventions.
#pragma once
#include <string>

#include "engine/RunConfig.hpp"
#include "io/InitialConditions.hpp"

namespace fountain {

class ParameterFile;

// The starting scale factor settled against the file's /Header/Time (cosmology.a_begin = 0
// takes it; a given one must agree to 1e-6), the file's cosmology checked against the
// parameters (to 1e-6), and the particles converted from the file's units and conventions to
// comoving code variables: x' and h' comoving, v' = a^2 dx/dt (from GADGET's v_pec / sqrt(a)
// or from v_pec), u' = a^2 u (u physical in files), the gas's temperature set as after
// recombination where the file gives no internal energy. Throws InputError naming the file,
// the field and the key.
void to_comoving_variables(io::InitialConditions& ic, RunConfig& config, const ParameterFile& params,
                           const std::string& path);

}  // namespace fountain
