#include "timestep/Integration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cooling/RadiativeCooling.hpp"
#include "gravity/GravityParams.hpp"
#include "core/Error.hpp"
#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"

namespace fountain {


int StepContext::courant_bin(std::size_t i) const {
  const double cs = hydro::sound_speed(gas.rho[i], gas.u[i], hydro.gamma);
  // Before this step's force loop: the signal velocity is the last force loop's.
  const double dt =
      hydro::hydro_timestep(gas.h[i], gas.div_v[i], cs, norm(gas.v[i]), std::max(gas.v_sig[i], 2.0 * cs), hydro);
  const int bin = std::min({timeline.bin_for(dt), timeline.bin_for(integration.dt_max),
                            TimeLine::largest_aligned_bin(ti_current)});
  return std::max(bin, 0);
}

namespace {

// exp(x), with the argument kept small: drifting h and rho is a prediction, not a law.
double bounded_exp(double x) { return std::exp(std::clamp(x, -0.2, 0.2)); }

// u after a kick, never dropping by more than half in one kick (as GADGET does) unless the
// rate came from the cooling task's implicit solve, which already ends the step at u > 0.
double kicked_energy(const StepContext& ctx, double u, double du_dt, double dt) {
  const double next = u + du_dt * dt;
  return next < 0.5 * u && !ctx.cooling ? 0.5 * u : next;
}

// The gravitational criterion of the paper (GADGET): sqrt(2 eta eps / |a|).
double gravity_timestep(const GravityParams& g, double softening, const Vec3& a) {
  const double a_norm = norm(a);
  return a_norm > 0.0 ? std::sqrt(2.0 * g.eta * softening / a_norm) : std::numeric_limits<double>::infinity();
}

}  // namespace

namespace integration {

std::string tick_text(const TimeLine& t) {
  return fmt::format("{:.4g}: the run from t = {:g} to run.t_end = {:g} is cut into 2^{} ticks", t.time_base(), t.t_begin,
                     t.t_end, TimeLine::max_bin);
}

void drift(StepContext& ctx, int c, ForceInputs force_inputs) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(c);
  const double dt = ctx.timeline.drift_factor(cell.ti_drift, ctx.ti_current);
  // The MSPH rule reads a neighbour's sound speed in the density loop, before its ghost.
  const bool ghost_prepares =
      force_inputs == ForceInputs::UnlessGhost && !ctx.hydro.msph && cell.ti_end_min == ctx.ti_current;
  const bool prepare = force_inputs != ForceInputs::Later;
  double h_max = 0.0;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (dt != 0.0) {
      gas.x[i] += gas.v_full[i] * dt;
      gas.v[i] += (gas.a_hydro[i] + gas.a_grav[i]) * dt;
      const double u_before = gas.u[i];
      gas.u[i] = kicked_energy(ctx, u_before, gas.du_dt[i], dt);
      // A safety net, as in the closing kick: the prediction never takes u below half of
      // the smaller of its value and the cooling floor, whatever changed the particle mid-step.
      if (ctx.cooling) gas.u[i] = std::max(gas.u[i], 0.5 * std::min(u_before, ctx.cooling->floor_energy()));
      // The prediction keeps to the floor the ghost holds (hydro.h_min_ratio).
      gas.h[i] = std::max(gas.h[i] * bounded_exp(gas.div_v[i] * dt / 3.0), ctx.hydro.h_min);
      gas.rho[i] *= bounded_exp(-gas.div_v[i] * dt);
    }
    gas.rho_msph[i] = gas.rho[i];
    gas.h_msph[i] = gas.h[i];
    if (prepare && (!ghost_prepares || !ctx.is_active(i))) hydro::prepare_force(gas, i, ctx.hydro);
    h_max = std::max(h_max, gas.h[i]);
  }
  if (dt != 0.0) {
    CollisionlessParticles& dm = ctx.dm;
    for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
      dm.x[i] += dm.v_full[i] * dt;
      dm.v[i] += dm.a_grav[i] * dt;
    }
  }
  cell.dx_max += cell.v_max * std::fabs(dt);
  cell.ti_drift = ctx.ti_current;
  cell.h_max = h_max;
  // A leaf without gas has no neighbours to cover (its cover is zero).
  if (cell.count > 0 && h_max + cell.dx_max + cell.dx_around > cell.r_cover) ctx.cover_exceeded = true;
}

void kick_close(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(c);
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    // The force loop gave the hydro force per unit gas mass; hidden stars add inertia
    // (momentum (m + m_hidden) v is what pairs exchange).
    if (gas.mass_stars_hidden[i] > 0.0) gas.a_hydro[i] *= gas.mass[i] / gas.dynamical_mass(i);
    // Half of the step that ends now (shorter than its bin's if the particle was woken).
    const double dt = 0.5 * ctx.timeline.kick_factor(gas.ti_begin[i], ctx.ti_current);
    if (dt != 0.0) {
      gas.v_full[i] += (gas.a_hydro[i] + gas.a_grav[i]) * dt;
      // du_dt is now the hydro rate at the step's end (the force loop just reset it); the
      // cooling part of the step being closed was set at its start and applies to this half too.
      const double u_half = gas.u_full[i];
      double u = u_half + gas.du_dt[i] * dt;
      if (u < 0.5 * u_half) u = 0.5 * u_half;  // hydro alone never halves u in one kick (GADGET)
      if (ctx.cooling) {
        u += gas.du_dt_cool[i] * dt;
        cell.radiated -= gas.mass[i] * gas.du_dt_cool[i] * dt;
        // A safety net only: the implicit solve ends the step near its solution (> the 1e4 K
        // energy); a hydro rate that changed sign during the step could otherwise overshoot.
        u = std::max(u, 0.5 * std::min(u_half, ctx.cooling->floor_energy()));
      }
      gas.u_full[i] = u;
    }
    gas.v[i] = gas.v_full[i];
    gas.u[i] = gas.u_full[i];
  }
  CollisionlessParticles& dm = ctx.dm;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i)
    if (ctx.is_active_dm(i)) {
      dm.v_full[i] += dm.a_grav[i] * (0.5 * ctx.timeline.kick_factor(dm.ti_begin[i], ctx.ti_current));
      dm.v[i] = dm.v_full[i];
    }
}

void timestep(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(c);
  const HydroParams& p = ctx.hydro;
  const int max_bin = std::min(ctx.timeline.bin_for(ctx.integration.dt_max),
                               TimeLine::largest_aligned_bin(ctx.ti_current));
  IntegerTime ti_end_min = TimeLine::ticks;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (ctx.is_active(i)) {
      const double rho = gas.rho[i], u = gas.u[i];
      if (!std::isfinite(rho) || !std::isfinite(u) || !std::isfinite(gas.du_dt[i]) ||
          !std::isfinite(norm(gas.a_hydro[i])) || !std::isfinite(norm(gas.x[i])))
        throw InputError(fmt::format("gas particle id {} has a non-finite state at t = {} "
                                     "(rho = {}, u = {}, du/dt = {}, |a| = {})",
                                     gas.id[i], ctx.timeline.time(ctx.ti_current), rho, u,
                                     gas.du_dt[i], norm(gas.a_hydro[i])));
      const double cs = hydro::sound_speed(rho, u, p.gamma);
      double dt = hydro::hydro_timestep(gas.h[i], gas.div_v[i], cs, norm(gas.v[i]), gas.v_sig[i], p);
      if (ctx.gravity.enabled)
        dt = std::min(dt, gravity_timestep(ctx.gravity, ctx.gravity.softening_gas, gas.a_hydro[i] + gas.a_grav[i]));
      if (dt < ctx.integration.dt_min)
        throw InputError(fmt::format("gas particle id {} needs a timestep {} below dt_min = {} at t = {} (h = {}, "
                                     "c = {}, |v| = {}, div v = {}, v_sig = {}, |a_hydro| = {}, |a_grav| = {})",
                                     gas.id[i], dt, ctx.integration.dt_min, ctx.timeline.time(ctx.ti_current),
                                     gas.h[i], cs, norm(gas.v[i]), gas.div_v[i], gas.v_sig[i], norm(gas.a_hydro[i]),
                                     norm(gas.a_grav[i])));
      int bin = std::min(ctx.timeline.bin_for(dt), max_bin);
      if (p.timestep_limiter) bin = std::min<int>(bin, gas.limit_bin[i]);
      gas.limit_bin[i] = kNoBin;
      gas.ti_begin[i] = ctx.ti_current;
      if (bin < 0)
        throw InputError(fmt::format("gas particle id {} needs a timestep {} at t = {}, shorter than one tick of the "
                                     "timeline ({})",
                                     gas.id[i], dt, ctx.timeline.time(ctx.ti_current), integration::tick_text(ctx.timeline)));
      gas.time_bin[i] = static_cast<TimeBin>(bin);
    }
    ti_end_min = std::min(ti_end_min, TimeLine::step_end(gas.time_bin[i], ctx.ti_current));
  }
  CollisionlessParticles& dm = ctx.dm;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
    if (ctx.is_active_dm(i)) {
      if (!std::isfinite(norm(dm.a_grav[i])) || !std::isfinite(norm(dm.x[i])) || !std::isfinite(norm(dm.v_full[i])))
        throw InputError(fmt::format("{} particle id {} has a non-finite state at t = {} (|x| = {}, |v| = {}, |a| = {})",
                                     species_name(dm.species[i]), dm.id[i], ctx.timeline.time(ctx.ti_current), norm(dm.x[i]), norm(dm.v_full[i]),
                                     norm(dm.a_grav[i])));
      const double dt = gravity_timestep(ctx.gravity, ctx.gravity.softening(dm.species[i]), dm.a_grav[i]);
      if (dt < ctx.integration.dt_min)
        throw InputError(fmt::format("{} particle id {} needs a timestep {} below dt_min = {} at t = {}",
                                     species_name(dm.species[i]), dm.id[i], dt, ctx.integration.dt_min, ctx.timeline.time(ctx.ti_current)));
      // Without gravity (stars spawned in a hydro-only run) nothing limits the step but dt_max.
      const int bin = std::isfinite(dt) ? std::min(ctx.timeline.bin_for(dt), max_bin) : max_bin;
      if (bin < 0)
        throw InputError(fmt::format("{} particle id {} needs a timestep {} at t = {}, shorter than one tick of the "
                                     "timeline ({})",
                                     species_name(dm.species[i]), dm.id[i], dt, ctx.timeline.time(ctx.ti_current),
                                     integration::tick_text(ctx.timeline)));
      dm.time_bin[i] = static_cast<TimeBin>(bin);
      dm.ti_begin[i] = ctx.ti_current;
    }
    ti_end_min = std::min(ti_end_min, TimeLine::step_end(dm.time_bin[i], ctx.ti_current));
  }
  cell.ti_end_min = ti_end_min;
}

void kick_open(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(c);
  double v_max = 0.0;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (ctx.is_active(i)) {
      const double dt = 0.5 * ctx.timeline.step(gas.time_bin[i]);
      gas.v_full[i] += (gas.a_hydro[i] + gas.a_grav[i]) * dt;
      gas.u_full[i] = kicked_energy(ctx, gas.u_full[i], gas.du_dt[i], dt);
      cell.radiated -= gas.mass[i] * gas.du_dt_cool[i] * dt;
    }
    v_max = std::max(v_max, norm(gas.v_full[i]));
  }
  cell.v_max = v_max;
  CollisionlessParticles& dm = ctx.dm;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i)
    if (ctx.is_active_dm(i)) dm.v_full[i] += dm.a_grav[i] * (0.5 * ctx.timeline.step(dm.time_bin[i]));
}

void wake(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(c);
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    const int w = gas.wake_bin[i];
    if (w == kNoBin) continue;
    gas.wake_bin[i] = kNoBin;
    const int b = gas.time_bin[i];
    if (w >= b) continue;
    const IntegerTime old_end = gas.ti_begin[i] + TimeLine::step_ticks(b);
    const IntegerTime new_end = TimeLine::step_end(w, ctx.ti_current);
    if (new_end >= old_end) continue;
    // Take back the part of the opening kick that belonged to the cut-off end of the step.
    const double undo = 0.5 * ctx.timeline.kick_factor(new_end, old_end);
    gas.v_full[i] -= (gas.a_hydro[i] + gas.a_grav[i]) * undo;
    gas.u_full[i] -= gas.du_dt[i] * undo;
    cell.radiated += gas.mass[i] * gas.du_dt_cool[i] * undo;
    gas.time_bin[i] = static_cast<TimeBin>(w);
    cell.ti_end_min = std::min(cell.ti_end_min, new_end);
  }
}

}  // namespace integration
}  // namespace fountain
