// Initial conditions of the standard hydrodynamics validation problems (Sod, Sedov, Gresho).
#pragma once
#include <string>

#include "core/Vec3.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::ics {

struct ProblemIC {
  GasParticles gas;
  Vec3 box_size;
  bool periodic = true;
};

// SWIFT's SodShock_BCC_3D: periodic box 2 x 0.5 x 0.5, (rho, P) = (1, 1) for x < 1 on a BCC
// lattice of `cells_left` cells per unit length, (0.125, 0.1) for x > 1 with half as many,
// equal particle masses, at rest.
ProblemIC sod_shock(int cells_left, double gamma);

// Sedov-Taylor blast: periodic unit box, BCC lattice of `cells`^3 cells, rho = 1, P = p0,
// energy `energy` shared equally by the `hot_particles` particles nearest the centre.
ProblemIC sedov_blast(int cells, double gamma, double energy = 1.0, double p0 = 1e-6, int hot_particles = 15);

// Gresho-Chan vortex: rho = 1, the standard triangular azimuthal velocity and balancing
// pressure, in a periodic box 1 x 1 x (depth) with `cells` lattice cells per unit length;
// depth_cells = 0 takes half the box side (thinner slabs leave too few particles across).
ProblemIC gresho_vortex(int cells, double gamma, int depth_cells = 0);

// Evrard (1988) adiabatic collapse in its usual units (G = M = R = 1): a gas sphere at rest
// with rho = 1 / (2 pi r), from a cubic lattice of `cells_per_radius` points per unit length
// stretched radially (r -> r^(3/2)), and u = 0.05 G M / R. Open boundaries.
ProblemIC evrard_sphere(int cells_per_radius);

// The Gresho vortex's azimuthal velocity and pressure at radius r.
double gresho_velocity(double r);
double gresho_pressure(double r);

}  // namespace fountain::ics
