#include "analysis/Diagnostics.hpp"

#include <algorithm>
#include <limits>

namespace fountain::analysis {

Diagnostics measure(const GasParticles& gas, const CollisionlessParticles& dm, const TemperatureOf& temperature,
                    const FigurePhases& phases, double a) {
  Diagnostics d;
  // Plain runs: every factor is 1 and the sums are those of the state itself.
  const double density = 1.0 / (a * a * a), energy = 1.0 / (a * a), speed = 1.0 / a;
  double h_min = std::numeric_limits<double>::infinity();
  int bin_min = std::numeric_limits<int>::max();
  for (std::size_t i = 0; i < gas.size(); ++i) {
    const double m = gas.mass[i];
    h_min = std::min(h_min, a * gas.h[i]);
    bin_min = std::min<int>(bin_min, gas.time_bin[i]);
    const double m_dyn = gas.dynamical_mass(i);  // hidden stars move with the gas
    const Vec3 v = gas.v[i] * speed;
    const double v2 = dot(v, v), u = gas.u[i] * energy, potential = gas.potential[i] * speed;
    d.mass_gas += m;
    d.mass_stars_hidden += m_dyn - m;
    d.reservoir += gas.reservoir[i];
    const double t = temperature(u);
    const bool cold = phases.cold(t, gas.rho[i] * density);
    if (phases.hot(t)) d.mass_hot += m;
    else if (cold) d.mass_cold += m;
    else d.mass_warm += m;
    if (gas.promoted[i] && !cold) d.mass_promoted_diffuse += m;
    if (0.5 * v2 + potential > 0.0) d.mass_unbound += m;
    d.thermal += m * u;
    d.kinetic += 0.5 * m_dyn * v2;
    d.potential += 0.5 * m_dyn * potential;
    d.momentum += v * m_dyn;
    d.angular_momentum += cross(gas.x[i] * a, v) * m_dyn;
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    const double m = dm.mass[i];
    (dm.species[i] == Species::Star ? d.mass_stars : d.mass_dark_matter) += m;
    const Vec3 v = dm.v[i] * speed;
    d.kinetic += 0.5 * m * dot(v, v);
    d.potential += 0.5 * m * dm.potential[i] * speed;
    d.momentum += v * m;
    d.angular_momentum += cross(dm.x[i] * a, v) * m;
    bin_min = std::min<int>(bin_min, dm.time_bin[i]);
  }
  d.h_min_gas = gas.size() > 0 ? h_min : 0.0;
  d.time_bin_min = dm.size() + gas.size() > 0 ? bin_min : 0;
  return d;
}

}  // namespace fountain::analysis
