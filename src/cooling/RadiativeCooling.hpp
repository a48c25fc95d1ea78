// Optically thin radiative cooling from the SD93 tables, integrated implicitly (docs/physics.md §4).
#pragma once
#include "cooling/CoolingTable.hpp"
#include <vector>

#include "core/Units.hpp"

namespace fountain::cooling {

// All inputs and outputs in internal units; densities are physical (a comoving run passes
// rho / a^3). Cooling switches off at and below the table's 1e4 K: no artificial floor.
class RadiativeCooling {
 public:
  RadiativeCooling(const CoolingTable& table, const Units& units, double hydrogen_fraction = 0.76);

  // Temperature (K) of gas with specific energy u, with the table's mean particle mass at
  // that temperature (u(T) is monotonic, so it is solved by bisection, not iterated).
  double temperature(double u) const;
  double log10_temperature(double u) const;
  // Specific energy of gas at temperature T (K).
  double energy_at(double temperature_k) const;
  // The cooling term du/dt (<= 0) at density rho and specific energy u.
  double du_dt(double rho, double u) const;
  // u at the end of a step: solves u_new = u_old + dt (du_dt_hydro + du_dt(rho, u_new)),
  // bracketed between the 1e4 K energy and the value without cooling.
  double implicit_step(double rho, double u_old, double du_dt_hydro, double dt) const;
  // The specific energy at the table's lowest temperature, below which nothing cools.
  double floor_energy() const { return u_floor_; }

 private:
  const CoolingTable& table_;
  Units units_;
  double x_h_;
  double u_floor_;
  double u_max_;                    // energy at the table's highest temperature
  std::vector<double> log_u_nodes_;  // log u at the table's temperatures: brackets T(u)
};

}  // namespace fountain::cooling
