#include "cooling/CoolingLoop.hpp"

#include <algorithm>

#include "cooling/RadiativeCooling.hpp"

namespace fountain::cooling {

void cool_cell(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  const Cell& cell = ctx.space.cell(c);
  const RadiativeCooling& cooling = *ctx.cooling;
  const StepContext::Expansion& e = ctx.expansion;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    // The energy equation's factor over the step (the step itself in plain runs; int dt / a^2
    // for a comoving u') and its cosmic time, which the cooling rate integrates over.
    const StepContext::StepSpan span = ctx.step_span(gas.time_bin[i]);
    if (!(span.energy > 0.0)) continue;
    const double u_old = gas.u_full[i];
    // The hydro part keeps the rule the kicks apply without cooling: u never falls below half
    // in one step from hydrodynamics alone, so the bracket of the solve stays positive.
    const double du_hydro = std::max(gas.du_dt[i], -0.5 * u_old / span.energy);
    // Solved in physical u with a fixed at the step's start, where the forces were computed:
    // u_new = u_old + (du_hydro K_u / a^2) + K_t Lambda(u_new) (docs/physics.md §11).
    const double du_hydro_physical = e.energy(du_hydro) * (span.energy / span.time);
    const double u_new =
        e.code_energy(cooling.implicit_step(e.density(gas.rho[i]), e.energy(u_old), du_hydro_physical, span.time));
    gas.du_dt[i] = (u_new - u_old) / span.energy;
    // The kicks count what this part of the rate takes out (docs/design.md).
    gas.du_dt_cool[i] = (u_new - (u_old + du_hydro * span.energy)) / span.energy;
  }
}

}  // namespace fountain::cooling
