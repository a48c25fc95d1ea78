// Initial conditions of a periodic cosmological box: dark matter (and gas) on a lattice displaced by Zel'dovich or 2LPT from a Gaussian field.
#pragma once
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/Units.hpp"
#include "core/Vec3.hpp"
#include "cosmology/Background.hpp"
#include "cosmology/TransferFunction.hpp"
#include "ics/LagrangianPerturbation.hpp"
#include "particles/IcParticles.hpp"

namespace fountain::ics {

struct CosmologicalBoxParams {
  int level = 6;                 // N = 2^level particles per side and species
  double box = 100.0;            // side L, Mpc/h comoving
  double a_start = 0.02;         // z = 49
  std::uint64_t seed = 1;
  cosmology::CosmologyParams cosmology{};  // as a run's defaults
  double sigma_8 = 0.9;
  double n_s = 1.0;
  cosmology::TransferKind transfer = cosmology::TransferKind::full;
  int lpt_order = 2;             // 1: Zel'dovich, 2: second order
  bool gas = true;               // gas at the cells' far corners, Omega_b / Omega_m of the mass
  // Variance suppression (Angulo & Pontzen 2016), as monofonIC's DoInversion and DoFixing: the
  // same noise with every mode's sign reversed (a pair's mean cancels the realisation's
  // second-order term), and every mode's amplitude set to its mean (only its phase random).
  bool invert_phases = false;
  bool fix_amplitudes = false;
  int cells() const { return 1 << level; }
};

// The particles in code variables of a comoving run in h-scaled units (Mpc/h, Msun/h, km/s;
// positions comoving in [0, L), v' = a v_pec, u' = a^2 u of the decoupled gas's temperature).
// Dark matter of cell n = (i N + j) N + k has ID 1 + n, at q = (i + 1/2, j + 1/2, k + 1/2) L/N
// plus its displacement; the gas of that cell ID 1 + n + 2^40 at q + L/(2N) (1, 1, 1) plus the
// same fields there. Masses: Omega_m rho_crit0 (L/N)^3 per cell, split by Omega_b / Omega_m.
// Lean stores (what the file holds): to_run_particles gives an engine's.
struct CosmologicalBox {
  IcGasParticles gas;
  IcCollisionlessParticles dark_matter;
  double box = 0.0;
  double a = 0.0;
};
// `progress` (when set) hears each stage as it starts: long generations show where they are.
using IcProgress = std::function<void(const std::string& stage)>;
CosmologicalBox make_cosmological_box(const CosmologicalBoxParams& p, const Units& units, const IcProgress& progress = {});

// The linear density contrast at z = 0 (D = 1) the box is made from, as Fourier coefficients:
// each cell's white noise, transformed, times sqrt(P(k) / (L/N)^3) (and fixed or inverted as
// p asks).
SpectralField linear_density(const CosmologicalBoxParams& p);
// The same from a given white-noise grid of p.level (a zoom's nested noise).
SpectralField linear_density_of(const std::vector<double>& noise, const CosmologicalBoxParams& p);

// The particle of every cell of p.level's grid at a_start, cell c = (i N + j) N + k: into x[c]
// its Lagrangian position (the cell's centre, moved by `shift` cells along each axis) plus its
// displacement, not folded into the box, and into v[c] its velocity
// v' = a^2 H (f D psi1 + f2 D2 grad phi2). `fields` are of the linear density on p.level's
// grid; one set serves every shift. Written a component at a time, straight into x and v.
void lattice_motion(DisplacementFields& fields, const CosmologicalBoxParams& p, double shift, std::span<Vec3> x,
                    std::span<Vec3> v);
// The same into vectors of their own (a zoom averages them over blocks of cells).
struct LatticeParticles {
  std::vector<Vec3> x, v;
};
LatticeParticles lagrangian_particles(DisplacementFields& fields, const CosmologicalBoxParams& p, double shift);

// Omega_m rho_crit0 (L/N)^3: the matter of one cell of p.level's grid.
double cell_matter(const CosmologicalBoxParams& p, int level, const Units& units);

}  // namespace fountain::ics
