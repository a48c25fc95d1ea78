// Star formation settings of a run (docs/physics.md, star formation).
#pragma once

#include "core/Units.hpp"

namespace fountain {

class ParameterFile;

struct StarFormationParams {
  bool enabled = false;
  double efficiency = 0.1;                 // c*
  double density_threshold_cgs = 5e-26;    // rho* (physical, g cm^-3)
  double temperature_threshold = 4e4;      // T* (K)
  double spawn_fraction = 0.3;             // hidden mass that becomes a star particle, of m_init
  double dissolve_fraction = 0.1;          // gas mass at which a particle dissolves, of m_init


  // In internal units.
  double density_threshold(const Units& u) const { return density_threshold_cgs / u.density_cgs(); }

  static StarFormationParams from(const ParameterFile& p);
};

}  // namespace fountain
