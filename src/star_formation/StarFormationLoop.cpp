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
    // The conditions and the rate are physical (comoving: at the step's start, where the
    // forces were computed), over the step's cosmic time.
    const StepContext::Expansion& e = ctx.expansion;
    const double dt = ctx.step_span(gas.time_bin[i]).time;
    const GasState s{e.divergence(gas.div_v[i]), e.density(gas.rho[i]), e.length(gas.h[i]),
                     e.speed(hydro::sound_speed(gas.rho[i], gas.u[i], ctx.hydro.gamma)), sf.temperature(e.energy(gas.u[i]))};
    if (dt > 0.0 && sf.law.check(s) == Eligibility::Eligible) {
      const double dm = sf.law.mass_formed(gas.mass[i], s.rho, dt);
      gas.mass[i] -= dm;
      gas.mass_stars_hidden[i] += dm;
      cf.tally.mass_formed += dm;
      cf.tally.thermal_locked += dm * e.energy(gas.u_full[i]);
      feedback::deposit(ctx, fb, i, dm, cf);
    }
    feedback::list_site(fb, gas, i, cf);
  }
}

bool due_to_spawn(const GasParticles& gas, const StarFormationParams& p, std::size_t i) {
  return gas.mass[i] > 0.0 && gas.mass_stars_hidden[i] >= p.spawn_fraction * gas.mass_initial[i] * (1.0 - 1e-12);
}

bool due_to_dissolve(const GasParticles& gas, const StarFormationParams& p, std::size_t i) {
  return gas.mass[i] > 0.0 && gas.mass[i] <= p.dissolve_fraction * gas.mass_initial[i] * (1.0 + 1e-12);
}

void spawn(StepContext& ctx, StarFormationState& sf, std::size_t i, std::uint64_t id) {
  GasParticles& gas = ctx.gas;
  CollisionlessParticles& stars = ctx.dm;
  // The star starts half-kicked by gravity alone over the parent's current step: the
  // hydro part of its opening kick is taken back (comoving: with the hydro factor).
  const IntegerTime begin = gas.ti_begin[i];
  const double half_hydro =
      ctx.comoving ? ctx.comoving->hydro_kick(static_cast<double>(begin),
                                              static_cast<double>(begin) + 0.5 * static_cast<double>(TimeLine::step_ticks(gas.time_bin[i])))
                   : 0.5 * ctx.timeline.step(gas.time_bin[i]);
  const Vec3 v_full = gas.v_full[i] - gas.a_hydro[i] * half_hydro;
  stars.push_back(id, Species::Star, gas.mass_stars_hidden[i], gas.x[i], v_full, gas.v[i], sf.time, gas.id[i]);
  const std::size_t s = stars.size() - 1;
  stars.a_grav[s] = gas.a_grav[i];
  stars.a_mesh[s] = gas.a_mesh[i];
  stars.potential_mesh[s] = gas.potential_mesh[i];
  stars.potential[s] = gas.potential[i];
  stars.time_bin[s] = gas.time_bin[i];
  stars.ti_begin[s] = gas.ti_begin[i];
  gas.mass_stars_hidden[i] = 0.0;
  ++sf.step_tally.stars_spawned;
}

bool dissolve(StepContext& ctx, StarFormationState& sf, std::size_t i, const std::function<void(std::size_t)>& receiver) {
  GasParticles& gas = ctx.gas;
  StarFormationTally& tally = sf.step_tally;
  // The reservoir is physical energy; the particles' u' take a^2 of it, and the kinetic
  // energy their merger turns to heat is a^2 the physical one (v' = a v_pec).
  double kinetic_to_heat = 0.0;
  const bool shared = hydro::share_among_neighbours(ctx.space, gas, i, gas.mass[i], gas.mass_stars_hidden[i],
                                                    ctx.expansion.code_energy(gas.reservoir[i]),
                                                    [&](std::size_t j) {
                                                      if (receiver) receiver(j);
                                                      return true;
                                                    },
                                                    kinetic_to_heat);
  tally.kinetic_to_heat += ctx.expansion.energy(kinetic_to_heat);
  if (!shared) return false;
  tally.energy_released += gas.reservoir[i];
  gas.mass[i] = 0.0;
  gas.mass_stars_hidden[i] = 0.0;
  gas.reservoir[i] = 0.0;
  ++tally.gas_dissolved;
  return true;
}

bool spawn_and_dissolve(StepContext& ctx, StarFormationState& sf, std::uint64_t& next_id) {
  GasParticles& gas = ctx.gas;
  const StarFormationParams& p = sf.params;
  bool changed = false;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    if (due_to_spawn(gas, p, i)) {
      spawn(ctx, sf, i, next_id++);
      changed = true;
    }
    if (due_to_dissolve(gas, p, i) && dissolve(ctx, sf, i)) changed = true;
  }
  return changed;
}

}  // namespace fountain::star_formation
