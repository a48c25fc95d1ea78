// The rotating collapsing sphere of Navarro & White (1993), as rerun by Marri & White (2003)
// section 3: gas and dark matter on superposed cubic lattices, stretched radially to
// rho = M / (2 pi R^2 r), in solid-body rotation about z with a given spin parameter, the gas
// with a uniform specific thermal energy. Recipe and closed forms: docs/physics.md §8.1.
#pragma once
#include <cstdint>
#include <vector>

#include "core/Units.hpp"
#include "core/Vec3.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::ics {

struct RotatingSphereParams {
  // Target number of particles per species. The lattice spacing is chosen so that the DM and
  // gas counts together come as close to 2 N as the lattice allows (within ~1 % at N >= 1000).
  int particles_per_species = 4000;
  double total_mass = 1.0e12;      // M, gas + DM (internal mass units; default Msun/h)
  double radius = 0.1;             // R (internal length units; default Mpc/h = 100 kpc/h)
  double spin = 0.1;               // lambda = J |E|^(1/2) / (G M^(5/2))
  double thermal_fraction = 0.05;  // gas specific internal energy u = f |W| / M
  double gas_fraction = 0.1;       // M_gas / M
  double G = Units{}.gravitational_constant();  // Newton's constant in internal units
  // Plummer softening used only to sum W, in units of R (lattice points never coincide, so
  // this only guards against a jittered pair landing on each other).
  double potential_softening = 1.0e-6;
  // Random displacement of each lattice point before the cut and stretch, uniform in
  // [-jitter d/2, jitter d/2] per coordinate (d the lattice spacing); 0 = a perfect lattice.
  // With jitter the set is recentred on its centre of mass.
  double jitter = 0.0;
  std::uint64_t seed = 20030101;
  // Kernel-weighted neighbour number the initial smoothing lengths are estimated for,
  // h = (3 N_ngb m_gas / (4 pi rho_gas(r)))^(1/3) from the analytic profile; 0 writes h = 0
  // (the run then makes its own guess).
  double smoothing_neighbours = 32.0;
};

struct RotatingSphereIC {
  GasParticles gas;        // id 1..N_gas, mass, x, v = v_full, u = u_full, h
  CollisionlessParticles dm;  // id N_gas+1..N_gas+N_dm
  // What the construction found (internal units), all from the actual particle set.
  double lattice_spacing = 0.0;       // d, before the stretch
  double omega = 0.0;                 // angular velocity about z
  double u = 0.0;                     // gas specific internal energy
  double potential_energy = 0.0;      // W (< 0), direct sum over all pairs
  double rotational_energy = 0.0;     // K_rot = omega^2 I_z / 2
  double thermal_energy = 0.0;        // U = u M_gas
  double angular_momentum = 0.0;      // J_z = omega I_z
  double spin = 0.0;                  // J |E|^(1/2) / (G M^(5/2)) with E = W + K_rot + U
  int iterations = 0;                 // fixed-point iterations for omega
};

// Builds the sphere (throws InputError for nonsensical parameters). Deterministic: the same
// parameters give bitwise the same particles for any number of threads.
RotatingSphereIC rotating_sphere(const RotatingSphereParams& params);

// W = -sum_{i<j} G m_i m_j / sqrt(r_ij^2 + eps^2) over the given particles, by direct
// summation (parallel over rows, summed in a fixed order: deterministic).
double direct_potential_energy(const std::vector<Vec3>& x, const std::vector<double>& m, double G, double eps);

}  // namespace fountain::ics
