// O(N^2) reference sums for the SPH loops, used to check the cell/task loops.
#pragma once
#include <cmath>
#include <vector>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::test {

struct BruteForce {
  const GasParticles& gas;
  const HydroParams& p;
  bool periodic;
  Vec3 box;

  Vec3 separation(std::size_t i, std::size_t j) const {
    Vec3 d = gas.x[i] - gas.x[j];
    if (periodic)
      for (int k = 0; k < 3; ++k) {
        if (d[k] > 0.5 * box[k]) d[k] -= box[k];
        if (d[k] < -0.5 * box[k]) d[k] += box[k];
      }
    return d;
  }

  bool decoupled(std::size_t i, std::size_t j, const Vec3& dx, double r2) const {
    if (i == j) return false;
    return hydro::msph_decoupled(hydro::msph_state(gas, i), hydro::msph_state(gas, j), dx,
                                 gas.v[i] - gas.v[j], r2, p);
  }

  hydro::DensityResult density(std::size_t i, double h) const {
    hydro::DensitySums s;
    for (std::size_t j = 0; j < gas.size(); ++j) {
      const Vec3 dx = separation(i, j);
      const double r2 = dot(dx, dx);
      if (r2 >= h * h || decoupled(i, j, dx, r2)) continue;
      hydro::iact_density(dx, gas.v[i] - gas.v[j], r2, 1.0 / h, gas.mass[j], s);
    }
    return hydro::finish_density(s, h);
  }

  // The strain rate the viscosity's reconstruction reads, at smoothing length h.
  hydro::StrainRate strain(std::size_t i, double h) const {
    hydro::GradientSums s;
    for (std::size_t j = 0; j < gas.size(); ++j) {
      const Vec3 dx = separation(i, j);
      const double r2 = dot(dx, dx);
      if (r2 >= h * h || decoupled(i, j, dx, r2)) continue;
      hydro::iact_gradient(dx, gas.v[i] - gas.v[j], r2, 1.0 / h, gas.mass[j], s);
    }
    return hydro::strain_rate(s);
  }

  // The h at which the weighted neighbour number is exactly N_ngb (bisection).
  double solve_h(std::size_t i, double h_guess) const {
    double lo = 0.0, hi = h_guess;
    while (density(i, hi).wcount < p.neighbours) hi *= 1.5;
    for (int it = 0; it < 100 && hi - lo > 1e-13 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (density(i, mid).wcount < p.neighbours ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }

  hydro::ForceSums force(std::size_t i) const {
    auto state = [&](std::size_t k) {
      return hydro::make_force_state(gas.v[k], gas.mass[k], gas.rho[k], gas.u[k], gas.h[k], gas.div_v[k],
                                     gas.curl_v[k], p, {gas.strain_diagonal[k], gas.strain_shear[k]});
    };
    const auto fi = state(i);
    hydro::ForceSums s;
    for (std::size_t j = 0; j < gas.size(); ++j) {
      if (j == i) continue;
      const Vec3 dx = separation(i, j);
      const double r2 = dot(dx, dx);
      const double hm = std::max(gas.h[i], gas.h[j]);
      if (r2 >= hm * hm || decoupled(i, j, dx, r2)) continue;
      hydro::iact_force(fi, state(j), dx, r2, p, s);
    }
    return s;
  }

  std::size_t decoupled_pairs() const {
    std::size_t n = 0;
    for (std::size_t i = 0; i < gas.size(); ++i)
      for (std::size_t j = 0; j < gas.size(); ++j) {
        const Vec3 dx = separation(i, j);
        const double r2 = dot(dx, dx);
        if (r2 < gas.h[i] * gas.h[i] && decoupled(i, j, dx, r2)) ++n;
      }
    return n;
  }
};

}  // namespace fountain::test
