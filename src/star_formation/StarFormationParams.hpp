// Star formation and multiphase feedback settings of a run (docs/physics.md sections 5-6).
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

  // Feedback (MFB): e_sn per solar mass formed, split eps_c (reservoir), eps_h (hot
  // neighbours) and the rest (the particle's own u).
  double energy_per_solar_mass_erg = 4e48;
  double eps_cold = 0.0;
  double eps_hot = 0.0;
  int hot_neighbours = 10;
  double max_search_radius = 0.0;          // internal length; 0: no limit
  double promotion_factor = 50.0;          // T_prom >= this x T*
  double promotion_hot_factor = 2.0;       // T_prom >= this x the hot neighbours' mean T

  // In internal units.
  double density_threshold(const Units& u) const { return density_threshold_cgs / u.density_cgs(); }
  // Supernova energy per unit internal mass formed (internal specific energy).
  double energy_per_mass(const Units& u) const {
    constexpr double msun_g = 1.988409870698051e33;
    return energy_per_solar_mass_erg / msun_g / u.specific_energy_cgs();
  }

  static StarFormationParams from(const ParameterFile& p);
};

}  // namespace fountain
