// Conservative transfer of mass, momentum and energy from one gas particle to others (star formation's dissolving, feedback's promotion).
#pragma once
#include <cstddef>
#include <utility>
#include <vector>

#include "core/Vec3.hpp"
#include "hydro/Kernel.hpp"
#include "particles/GasParticles.hpp"
#include "space/NeighbourSearch.hpp"
#include "space/Space.hpp"

namespace fountain::hydro {

// Gas particle j takes gas mass dm_gas and hidden stellar mass dm_hidden moving at v_src
// with specific energy u_src, plus `heat` (energy). Mass and momentum are conserved exactly,
// and the predicted energy too: returns the kinetic energy the inelastic merger lost, which
// it gave j as heat.
double absorb(GasParticles& gas, std::size_t j, double dm_gas, double dm_hidden, const Vec3& v_src, double u_src,
              double heat);

// Shares (dm_gas, dm_hidden, heat) of particle i among gas neighbours within h_i that pass
// `accept`, in proportion to their kernel weight W(r_ij, h_i), adding the kinetic energy
// turned to heat to `kinetic_to_heat`. False, and nothing moved, if there are none.
template <class Accept>
bool share_among_neighbours(const Space& space, GasParticles& gas, std::size_t i, double dm_gas, double dm_hidden,
                            double heat, Accept accept, double& kinetic_to_heat) {
  std::vector<std::pair<std::size_t, double>> to;
  double w_sum = 0.0;
  const double h_inv = 1.0 / gas.h[i];
  for_each_within(space, gas, gas.x[i], gas.h[i], [&](std::size_t j, const Vec3&, double r) {
    if (j == i || !(gas.mass[j] > 0.0) || !accept(j)) return;
    const double w = kernel::value(r, h_inv);
    if (w > 0.0) {
      to.emplace_back(j, w);
      w_sum += w;
    }
  });
  if (to.empty()) return false;
  const Vec3 v_i = gas.v[i];
  const double u_i = gas.u[i];
  for (const auto& [j, w] : to) {
    const double f = w / w_sum;
    kinetic_to_heat += absorb(gas, j, f * dm_gas, f * dm_hidden, v_i, u_i, f * heat);
  }
  return true;
}

}  // namespace fountain::hydro
