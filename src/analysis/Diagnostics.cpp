#include "analysis/Diagnostics.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

namespace fountain::analysis {

DiagnosticsSum::DiagnosticsSum(TemperatureOf temperature, const FigurePhases& phases, double a)
    : temperature_(std::move(temperature)),
      phases_(phases),
      a_(a),
      h_min_(std::numeric_limits<double>::infinity()),
      bin_min_(std::numeric_limits<int>::max()) {}

void DiagnosticsSum::add_gas(const GasParticles& gas, std::size_t first, std::size_t count) {
  if (collisionless_ > 0) throw std::logic_error("gas summed after collisionless particles");
  Diagnostics& d = d_;
  const double a = a_;
  // Plain runs: every factor is 1 and the sums are those of the state itself.
  const double density = 1.0 / (a * a * a), energy = 1.0 / (a * a), speed = 1.0 / a;
  for (std::size_t i = first; i < first + count; ++i) {
    const double m = gas.mass[i];
    h_min_ = std::min(h_min_, a * gas.h[i]);
    bin_min_ = std::min<int>(bin_min_, gas.time_bin[i]);
    const double m_dyn = gas.dynamical_mass(i);  // hidden stars move with the gas
    const Vec3 v = gas.v[i] * speed;
    const double v2 = dot(v, v), u = gas.u[i] * energy, potential = gas.potential[i] * speed;
    d.mass_gas += m;
    d.mass_stars_hidden += m_dyn - m;
    d.reservoir += gas.reservoir[i];
    const double t = temperature_(u);
    const bool cold = phases_.cold(t, gas.rho[i] * density);
    if (phases_.hot(t)) d.mass_hot += m;
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
  gas_ += count;
}

void DiagnosticsSum::add_collisionless(const CollisionlessParticles& p, std::size_t first, std::size_t count) {
  Diagnostics& d = d_;
  const double a = a_, speed = 1.0 / a;
  for (std::size_t i = first; i < first + count; ++i) {
    const double m = p.mass[i];
    (p.species[i] == Species::Star ? d.mass_stars : d.mass_dark_matter) += m;
    const Vec3 v = p.v[i] * speed;
    d.kinetic += 0.5 * m * dot(v, v);
    d.potential += 0.5 * m * p.potential[i] * speed;
    d.momentum += v * m;
    d.angular_momentum += cross(p.x[i] * a, v) * m;
    bin_min_ = std::min<int>(bin_min_, p.time_bin[i]);
  }
  collisionless_ += count;
}

Diagnostics DiagnosticsSum::result() const {
  Diagnostics d = d_;
  d.h_min_gas = gas_ > 0 ? h_min_ : 0.0;
  d.time_bin_min = gas_ + collisionless_ > 0 ? bin_min_ : 0;
  return d;
}

Diagnostics measure(const GasParticles& gas, const CollisionlessParticles& dm, const TemperatureOf& temperature,
                    const FigurePhases& phases, double a) {
  DiagnosticsSum sum(temperature, phases, a);
  sum.add_gas(gas, 0, gas.size());
  sum.add_collisionless(dm, 0, dm.size());
  return sum.result();
}

}  // namespace fountain::analysis
