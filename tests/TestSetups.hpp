// Small particle sets and run configurations shared by the tests.
#pragma once
#include <functional>
#include <numbers>
#include <random>

#include "engine/RunConfig.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::test {

inline RunConfig test_config(bool periodic, const Vec3& box, bool msph, int threads = 2) {
  RunConfig c;
  c.t_begin = 0.0;
  c.t_end = 1.0;
  c.threads = threads;
  c.hydro.msph = msph;
  c.hydro.neighbours = 32;
  c.hydro.neighbours_tolerance = 1e-6;
  c.hydro.max_h_iterations = 100;
  c.integration.dt_min = 1e-12;
  c.integration.dt_max = 1e-2;
  c.space.periodic = periodic;
  c.space.box_size = box;
  c.space.split_size = 32;
  return c;
}

// n particles uniformly at random in [lo, lo + size), random velocities and energies.
inline void add_random(GasParticles& g, std::size_t n, const Vec3& lo, const Vec3& size, double mass, double u,
                       double v_scale, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const std::size_t start = g.size();
  g.resize(start + n);
  for (std::size_t k = start; k < start + n; ++k) {
    g.id[k] = k + 1;
    g.mass[k] = mass;
    g.x[k] = lo + Vec3{U(rng) * size.x, U(rng) * size.y, U(rng) * size.z};
    g.v[k] = g.v_full[k] = Vec3{U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5} * v_scale;
    g.u[k] = g.u_full[k] = u * (0.5 + U(rng));
    g.h[k] = 0.0;
    g.time_bin[k] = 0;
  }
}

// rho_crit0 in Msun/h per (Mpc/h)^3 with Fountain's G (internal units Mpc, Msun, km/s; H0 = 100).
inline double critical_density() {
  return 3.0 * 100.0 * 100.0 / (8.0 * std::numbers::pi * Units().gravitational_constant());
}

// Gas on a cubic lattice of n^3 cells in a periodic box of side L, the whole matter content of
// the universe (Omega_m = Omega_b: gas only), with comoving energy u' and velocity v'(x) (at
// rest by default).
inline GasParticles lattice_gas(int n, double box, double omega_m, double u_comoving,
                                const std::function<Vec3(const Vec3&)>& velocity = {}) {
  GasParticles g;
  g.resize(static_cast<std::size_t>(n) * n * n);
  const double spacing = box / n;
  const double mass = omega_m * critical_density() * box * box * box / static_cast<double>(g.size());
  std::size_t k = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int l = 0; l < n; ++l, ++k) {
        g.id[k] = k + 1;
        g.mass[k] = mass;
        g.x[k] = {(i + 0.5) * spacing, (j + 0.5) * spacing, (l + 0.5) * spacing};
        g.v[k] = g.v_full[k] = velocity ? velocity(g.x[k]) : Vec3{};
        g.u[k] = g.u_full[k] = u_comoving;
        g.h[k] = 0.0;
      }
  return g;
}

// A comoving run of a periodic box (gas only unless the caller adds dark matter: Omega_b =
// Omega_m, h = 1) from a_begin to a_end with TreePM on a mesh of `mesh` cells; steps bound by
// 0.01 in ln a and the particles' criteria.
inline RunConfig comoving_config(double box, double omega_m, double omega_lambda, double a_begin, double a_end, int mesh) {
  RunConfig c;
  c.threads = 2;
  c.comoving.enabled = true;
  c.comoving.cosmology = {omega_m, omega_lambda, omega_m, 1.0};
  c.comoving.a_begin = a_begin;
  c.comoving.a_end = a_end;
  c.hydro.neighbours = 32;
  c.hydro.neighbours_tolerance = 1e-6;
  c.hydro.max_h_iterations = 100;
  c.integration.dt_min = 1e-12;
  c.integration.dt_max = 1.0;  // the step in ln a (0.01) and the particles' criteria rule
  c.integration.max_dln_a = 0.01;
  c.space.periodic = true;
  c.space.box_size = {box, box, box};
  c.gravity.enabled = true;
  c.gravity.mesh_cells = mesh;
  c.gravity.G = Units().gravitational_constant();
  return c;
}

}  // namespace fountain::test
