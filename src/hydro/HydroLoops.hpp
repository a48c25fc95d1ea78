// The SPH loops over cells that the density, ghost and force tasks run.
#pragma once
#include "step/StepContext.hpp"
#include "hydro/HydroIact.hpp"

namespace fountain::hydro {

// Density loop, gather form: the sums of the active particles of `ci` over its own and its
// neighbour cells' particles, in one task (it writes only `ci`).
void density(StepContext& ctx, int ci);

// The ghost: turns the sums into densities and solves each active particle's h so that
// its weighted neighbour number is N_ngb within the tolerance (Newton with bisection).
void ghost(StepContext& ctx, int ci);

// Force loop, gather form: accelerations, du/dt and timestep-limiter bins of the active
// particles of `ci`, over its own and its neighbour cells' particles, in one task.
void force(StepContext& ctx, int ci);

// The state the MSPH rule sees of particle i this step.
inline MsphState msph_state(const GasParticles& gas, std::size_t i) {
  return {gas.rho_msph[i], gas.u[i], gas.h_msph[i], gas.soundspeed[i]};
}

// Fills particle i's prepared force inputs (pressure, sound speed, rho powers, Balsara)
// from its predicted state; the drift and the ghost call it.
// hubble_flow: a^2 H in a comoving run (StepContext::expansion), 0 otherwise.
void prepare_force(GasParticles& gas, std::size_t i, const HydroParams& p, double hubble_flow = 0.0);

// Particle i's force inputs, as prepared.
inline ForceState force_state(const GasParticles& gas, std::size_t i) {
  return {gas.v[i],           gas.mass[i],        gas.rho[i],
          gas.h[i],           gas.soundspeed[i],  gas.p_over_rho_a[i],
          gas.inv_rho_2ma[i], gas.balsara[i],     gas.entropy[i],
          {gas.strain_diagonal[i], gas.strain_shear[i]}};
}

}  // namespace fountain::hydro
