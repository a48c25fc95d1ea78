// Internal unit system and the physical constants expressed in it.
#pragma once

namespace fountain {

// Internal units as multiples of cgs units. The paper's defaults: length Mpc/h, mass Msun/h,
// velocity km/s (the 1/h is carried by the numbers, as in GADGET; no h appears here).
struct Units {
  double length_cgs = 3.0856775814913673e24;  // cm
  double mass_cgs = 1.988409870698051e33;     // g
  double velocity_cgs = 1.0e5;                // cm/s

  double time_cgs() const { return length_cgs / velocity_cgs; }
  double density_cgs() const { return mass_cgs / (length_cgs * length_cgs * length_cgs); }
  double energy_cgs() const { return mass_cgs * velocity_cgs * velocity_cgs; }
  double specific_energy_cgs() const { return velocity_cgs * velocity_cgs; }
  double pressure_cgs() const { return density_cgs() * velocity_cgs * velocity_cgs; }
  // Newton's constant in internal units.
  double gravitational_constant() const {
    constexpr double G_cgs = 6.67430e-8;
    return G_cgs * mass_cgs * time_cgs() * time_cgs() / (length_cgs * length_cgs * length_cgs);
  }
};

}  // namespace fountain
