#include "star_formation/StarFormationLoop.hpp"

#include <algorithm>
#include <cmath>

#include "hydro/HydroIact.hpp"
#include "hydro/MassTransfer.hpp"

namespace fountain::star_formation {

void form_stars(StepContext& ctx, const StarFormationState& sf, feedback::FeedbackState& fb, int c) {
  GasParticles& gas = ctx.gas;
  const Cell& cell = ctx.space.cell(c);
  feedback::CellFeedback& cf = fb.cells[static_cast<std::size_t>(c)];
  cf.sites.clear();
  cf.neighbours.clear();
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.feedback_hot_energy[i] = 0.0;  // none for the hot neighbours unless it forms stars now
    const double dt = ctx.timeline.step(gas.time_bin[i]);
    const GasState s{gas.div_v[i], gas.rho[i], gas.h[i], hydro::sound_speed(gas.rho[i], gas.u[i], ctx.hydro.gamma),
                     sf.temperature(gas.u[i])};
    if (dt > 0.0 && sf.law.check(s) == Eligibility::Eligible) {
      const double dm = sf.law.mass_formed(gas.mass[i], gas.rho[i], dt);
      gas.mass[i] -= dm;
      gas.mass_stars_hidden[i] += dm;
      cf.tally.mass_formed += dm;
      cf.tally.thermal_locked += dm * gas.u_full[i];
      feedback::deposit(fb, gas, i, dm, cf);
    }
    feedback::list_site(fb, gas, i, cf);
  }
}




bool spawn_and_dissolve(StepContext& ctx, StarFormationState& sf, std::uint64_t& next_id) {
  GasParticles& gas = ctx.gas;
  CollisionlessParticles& stars = ctx.dm;
  StarFormationTally& tally = sf.step_tally;
  const StarFormationParams& p = sf.params;
  bool changed = false;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    if (!(gas.mass[i] > 0.0)) continue;
    const double m0 = gas.mass_initial[i];
    if (gas.mass_stars_hidden[i] >= p.spawn_fraction * m0 * (1.0 - 1e-12)) {
      // The star starts half-kicked by gravity alone over the parent's current step.
      const double half = 0.5 * ctx.timeline.step(gas.time_bin[i]);
      const Vec3 v_full = gas.v_full[i] - gas.a_hydro[i] * half;
      stars.push_back(next_id++, Species::Star, gas.mass_stars_hidden[i], gas.x[i], v_full, gas.v[i], sf.time,
                      gas.id[i]);
      const std::size_t s = stars.size() - 1;
      stars.a_grav[s] = gas.a_grav[i];
      stars.a_mesh[s] = gas.a_mesh[i];
      stars.potential_mesh[s] = gas.potential_mesh[i];
      stars.potential[s] = gas.potential[i];
      stars.time_bin[s] = gas.time_bin[i];
      stars.ti_begin[s] = gas.ti_begin[i];
      gas.mass_stars_hidden[i] = 0.0;
      ++tally.stars_spawned;
      changed = true;
    }
    if (gas.mass[i] <= p.dissolve_fraction * m0 * (1.0 + 1e-12)) {
      const bool shared =
          hydro::share_among_neighbours(ctx.space, gas, i, gas.mass[i], gas.mass_stars_hidden[i], gas.reservoir[i],
                                        [](std::size_t) { return true; }, tally.kinetic_to_heat);
      if (shared) {
        tally.energy_released += gas.reservoir[i];
        gas.mass[i] = 0.0;
        gas.mass_stars_hidden[i] = 0.0;
        gas.reservoir[i] = 0.0;
        ++tally.gas_dissolved;
        changed = true;
      }
    }
  }
  return changed;
}

}  // namespace fountain::star_formation
