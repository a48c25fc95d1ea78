#include "cooling/CoolingLoop.hpp"

#include <algorithm>

#include "cooling/RadiativeCooling.hpp"

namespace fountain::cooling {

void cool_cell(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  const Cell& cell = ctx.space.cell(c);
  const RadiativeCooling& cooling = *ctx.cooling;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    const double dt = ctx.timeline.step(gas.time_bin[i]);
    if (!(dt > 0.0)) continue;
    const double u_old = gas.u_full[i];
    // The hydro part keeps the rule the kicks apply without cooling: u never falls below half
    // in one step from hydrodynamics alone, so the bracket of the solve stays positive.
    const double du_hydro = std::max(gas.du_dt[i], -0.5 * u_old / dt);
    const double u_new = cooling.implicit_step(gas.rho[i], u_old, du_hydro, dt);
    gas.du_dt[i] = (u_new - u_old) / dt;
    // The kicks count what this part of the rate takes out (docs/design.md).
    gas.du_dt_cool[i] = (u_new - (u_old + du_hydro * dt)) / dt;
  }
}

}  // namespace fountain::cooling
