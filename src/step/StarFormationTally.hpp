// Running sums of what star formation and its feedback did: mass formed, energy per channel, events.
// Both modules write it and the engine, io and messages read it, so it lives below them all.
#pragma once

namespace fountain::star_formation {

struct StarFormationTally {
  double mass_formed = 0.0;        // gas turned into (hidden) stars
  double thermal_locked = 0.0;     // thermal energy of that gas, gone with it into stars
  double energy_own = 0.0;         // feedback to the star-forming particle's own u
  double energy_reservoir = 0.0;   // feedback put into reservoirs (eps_c)
  double energy_hot = 0.0;         // feedback given to hot neighbours (eps_h)
  double energy_released = 0.0;    // reservoir energy let out: at promotions, and with dissolved particles
  double energy_promoted = 0.0;    // of energy_released, what promotions put into their particles' u
  double kinetic_to_heat = 0.0;    // kinetic energy of inelastic mass transfers, given as heat
  long long promotions = 0;
  long long stars_spawned = 0;
  long long gas_dissolved = 0;
  long long hot_without_neighbours = 0;  // eps_h given to the particle itself: no hot gas in reach

  StarFormationTally& operator+=(const StarFormationTally& o) {
    mass_formed += o.mass_formed; thermal_locked += o.thermal_locked; energy_own += o.energy_own;
    energy_reservoir += o.energy_reservoir; energy_hot += o.energy_hot; energy_released += o.energy_released;
    energy_promoted += o.energy_promoted;
    kinetic_to_heat += o.kinetic_to_heat; promotions += o.promotions; stars_spawned += o.stars_spawned;
    gas_dissolved += o.gas_dissolved; hot_without_neighbours += o.hot_without_neighbours;
    return *this;
  }
  bool operator==(const StarFormationTally&) const = default;
  // Feedback energy injected (own + reservoir + hot), as e_sn x mass formed.
  double energy_injected() const { return energy_own + energy_reservoir + energy_hot; }
};

}  // namespace fountain::star_formation
