// Multiphase supernova feedback settings of a run (docs/physics.md, feedback).
#pragma once

#include "core/Units.hpp"

namespace fountain {

class ParameterFile;

// The energy e_sn per solar mass of stars formed, split eps_c (the cold phase's reservoir),
// eps_h (the nearest hot neighbours) and the rest (the star-forming particle's own u).
struct FeedbackParams {
  double energy_per_solar_mass_erg = 4e48;
  double eps_cold = 0.0;
  double eps_hot = 0.0;
  int hot_neighbours = 10;
  double max_search_radius = 0.0;          // internal length; 0: no limit
  double promotion_factor = 50.0;          // T_prom >= this x T*
  double promotion_hot_factor = 2.0;       // T_prom >= this x the hot neighbours' mean T

  // Supernova energy per unit internal mass formed (internal specific energy).
  double energy_per_mass(const Units& u) const {
    constexpr double msun_g = 1.988409870698051e33;
    return energy_per_solar_mass_erg / msun_g / u.specific_energy_cgs();
  }
  // Whether anything but the particle's own heating happens (sites to list and search).
  bool has_sites() const { return eps_hot > 0.0 || eps_cold > 0.0; }

  static FeedbackParams from(const ParameterFile& p);
};

}  // namespace fountain
