// The temperature of gas of a given specific energy, for runs that have no cooling tables to ask.
#pragma once
#include <functional>

#include "core/Units.hpp"

namespace fountain {

// Temperature (K) of gas of specific energy u (internal units).
using TemperatureOf = std::function<double(double u)>;

// T = (gamma - 1) mu m_p u / k_B: a fully ionised primordial gas (mean molecular weight 0.59)
// unless told otherwise. Runs with cooling use the tables' own mean particle mass instead.
inline double ideal_gas_kelvin_per_energy(const Units& units, double gamma, double mean_molecular_weight = 0.59) {
  constexpr double k_boltzmann = 1.380649e-16, m_proton = 1.67262192e-24;
  return (gamma - 1.0) * mean_molecular_weight * m_proton / k_boltzmann * units.specific_energy_cgs();
}

inline TemperatureOf ideal_gas_temperature(const Units& units, double gamma, double mean_molecular_weight = 0.59) {
  const double factor = ideal_gas_kelvin_per_energy(units, gamma, mean_molecular_weight);
  return [factor](double u) { return factor * u; };
}

}  // namespace fountain
