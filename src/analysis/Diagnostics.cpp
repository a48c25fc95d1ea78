#include "analysis/Diagnostics.hpp"

#include <algorithm>
#include <limits>

namespace fountain::analysis {

Diagnostics measure(const GasParticles& gas, const CollisionlessParticles& dm, const TemperatureOf& temperature,
                    const FigurePhases& phases) {
  Diagnostics d;
  double h_min = std::numeric_limits<double>::infinity();
  int bin_min = std::numeric_limits<int>::max();
  for (std::size_t i = 0; i < gas.size(); ++i) {
    const double m = gas.mass[i];
    h_min = std::min(h_min, gas.h[i]);
    bin_min = std::min<int>(bin_min, gas.time_bin[i]);
    const double m_dyn = gas.dynamical_mass(i);  // hidden stars move with the gas
    const double v2 = dot(gas.v[i], gas.v[i]);
    d.mass_gas += m;
    d.mass_stars_hidden += m_dyn - m;
    d.reservoir += gas.reservoir[i];
    const double t = temperature(gas.u[i]);
    const bool cold = phases.cold(t, gas.rho[i]);
    if (phases.hot(t)) d.mass_hot += m;
    else if (cold) d.mass_cold += m;
    else d.mass_warm += m;
    if (gas.promoted[i] && !cold) d.mass_promoted_diffuse += m;
    if (0.5 * v2 + gas.potential[i] > 0.0) d.mass_unbound += m;
    d.thermal += m * gas.u[i];
    d.kinetic += 0.5 * m_dyn * v2;
    d.potential += 0.5 * m_dyn * gas.potential[i];
    d.momentum += gas.v[i] * m_dyn;
    d.angular_momentum += cross(gas.x[i], gas.v[i]) * m_dyn;
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    const double m = dm.mass[i];
    (dm.species[i] == Species::Star ? d.mass_stars : d.mass_dark_matter) += m;
    d.kinetic += 0.5 * m * dot(dm.v[i], dm.v[i]);
    d.potential += 0.5 * m * dm.potential[i];
    d.momentum += dm.v[i] * m;
    d.angular_momentum += cross(dm.x[i], dm.v[i]) * m;
    bin_min = std::min<int>(bin_min, dm.time_bin[i]);
  }
  d.h_min_gas = gas.size() > 0 ? h_min : 0.0;
  d.time_bin_min = dm.size() + gas.size() > 0 ? bin_min : 0;
  return d;
}

}  // namespace fountain::analysis
