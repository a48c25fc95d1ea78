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


void StepContext::set_time(IntegerTime ti) {
  ti_current = ti;
  if (!comoving) return;
  const double t = static_cast<double>(ti);
  expansion.a = comoving->scale_factor(t);
  expansion.hubble = comoving->hubble(t);
  expansion.hubble_flow = expansion.a * expansion.a * expansion.hubble;
  softening_factor = gravity.softening_factor(expansion.a);
}

StepContext::StepSpan StepContext::step_span(int bin) const {
  if (!comoving) {
    const double dt = timeline.step(bin);
    return {dt, dt};
  }
  const double begin = static_cast<double>(ti_current), end = begin + static_cast<double>(TimeLine::step_ticks(bin));
  return {comoving->cosmic_time(begin, end), comoving->drift(begin, end)};
}

double StepContext::softening_gas() const { return softening_factor * gravity.softening_gas; }
double StepContext::softening_of(std::size_t j) const {
  return softening_factor * gravity.softening(dm.species[j], dm.mass[j]);
}

namespace {

// The Courant step of gas particle i. A comoving run's state is comoving (x', v', h', rho',
// u' with u = u' / a^2 for gamma = 5/3); the criterion is physical: h = a h', c = c' / a,
// |v| = |v'| / a, div v = D' / a^2 + 3 H, and the signal velocity (its pair velocities carry
// the Hubble flow) v_sig' / a.
double courant_dt(const StepContext& ctx, std::size_t i, double v_sig) {
  const GasParticles& gas = ctx.gas;
  const double cs = hydro::sound_speed(gas.rho[i], gas.u[i], ctx.hydro.gamma);
  if (!ctx.comoving) return hydro::hydro_timestep(gas.h[i], gas.div_v[i], cs, norm(gas.v[i]), v_sig, ctx.hydro);
  const double a = ctx.expansion.a;
  return hydro::hydro_timestep(a * gas.h[i], gas.div_v[i] / (a * a) + 3.0 * ctx.expansion.hubble, cs / a,
                               norm(gas.v[i]) / a, v_sig / a, ctx.hydro);
}

// The bin of a physical step dt, capped by dt_max (and, comoving, the largest step in ln a).
int bin_of(const StepContext& ctx, double dt) {
  if (!ctx.comoving) return std::min(ctx.timeline.bin_for(dt), ctx.timeline.bin_for(ctx.integration.dt_max));
  return ctx.comoving->bin_for(std::min(dt, ctx.integration.dt_max), ctx.ti_current, ctx.integration.max_dln_a);
}
// The same for a gas or collisionless particle of a comoving run, with its species' RMS
// displacement limit.
int gas_bin_of(const StepContext& ctx, double dt) { return bin_of(ctx, std::min(dt, ctx.dt_rms_gas)); }

}  // namespace

int StepContext::courant_bin(std::size_t i) const {
  const double cs = hydro::sound_speed(gas.rho[i], gas.u[i], hydro.gamma);
  // Before this step's force loop: the signal velocity is the last force loop's.
  const double dt = courant_dt(*this, i, std::max(gas.v_sig[i], 2.0 * cs));
  int bin = std::min(bin_of(*this, dt), TimeLine::largest_aligned_bin(ti_current));
  if (mesh_step.active()) bin = std::min(bin, mesh_step.bin);
  return std::max(bin, 0);
}

namespace {

// The leapfrog's factors over ticks [t0, t1]: for gravity's acceleration, hydro's, and the
// energy equation's rate. Plain time: all three are the interval. Comoving: the integrals of
// dt/a, dt/a^(3 gamma - 3) and dt/a^2 (docs/physics.md §9).
struct KickFactors {
  double gravity, hydro, energy;
};
KickFactors comoving_kick(const StepContext& ctx, double t0, double t1) {
  return {ctx.comoving->gravity_kick(t0, t1), ctx.comoving->hydro_kick(t0, t1), ctx.comoving->drift(t0, t1)};
}
// The closing half kick of a step that began at ti_begin and ends now: from its midpoint on.
KickFactors closing_half(const StepContext& ctx, IntegerTime ti_begin) {
  const double end = static_cast<double>(ctx.ti_current);
  return comoving_kick(ctx, 0.5 * (static_cast<double>(ti_begin) + end), end);
}
// The opening half kick of a step of `bin` that begins now: up to its midpoint.
KickFactors opening_half(const StepContext& ctx, int bin) {
  const double begin = static_cast<double>(ctx.ti_current);
  return comoving_kick(ctx, begin, begin + 0.5 * static_cast<double>(TimeLine::step_ticks(bin)));
}
// The particles of a leaf that close (open) their steps together mostly began them together
// (take the same bin): each factor is worked out once for a run of them, the same value.
template <class Key, KickFactors (*kHalf)(const StepContext&, Key)>
struct HalfKicks {
  const StepContext& ctx;
  Key key = -1;
  KickFactors k{};
  const KickFactors& at(Key next) {
    if (next != key) {
      k = kHalf(ctx, next);
      key = next;
    }
    return k;
  }
};
using ClosingHalves = HalfKicks<IntegerTime, closing_half>;
using OpeningHalves = HalfKicks<int, opening_half>;

// With a mesh step, a particle's own kicks take the tree's part of its gravity; the mesh's
// part kicks over the mesh step's halves instead (docs/physics.md §11, "The mesh step").
Vec3 particle_gravity(const StepContext& ctx, const Vec3& a_grav, const Vec3& a_mesh) {
  return ctx.mesh_step.active() ? a_grav - a_mesh : a_grav;
}
// The mesh's closing and opening half kicks, at the start of a mesh step.
void mesh_close_kick(const StepContext& ctx, Vec3& v_full, const Vec3& a_mesh) {
  if (ctx.mesh_step.due) v_full += a_mesh * ctx.mesh_step.close_kick;
}
void mesh_open_kick(const StepContext& ctx, Vec3& v_full, const Vec3& a_mesh) {
  if (ctx.mesh_step.due) v_full += a_mesh * ctx.mesh_step.open_kick;
}
// The velocity at ti_current of a particle whose own kicks just brought v_full there: inside
// a mesh step, v_full holds the mesh's kick to that step's midpoint.
Vec3 predicted_velocity(const StepContext& ctx, const Vec3& v_full, const Vec3& a_mesh) {
  if (!ctx.mesh_step.active() || ctx.mesh_step.due) return v_full;
  return v_full + a_mesh * ctx.mesh_step.predict_kick;
}

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

// The same in a comoving run, on physical quantities: softening a eps', acceleration
// A'_g / a^2 + A'_h / a^3 (gamma = 5/3).
double physical_gravity_timestep(const StepContext& ctx, double softening, const Vec3& a_grav, const Vec3& a_hydro) {
  const double a = ctx.expansion.a;
  return gravity_timestep(ctx.gravity, a * softening, a_grav * (1.0 / (a * a)) + a_hydro * (1.0 / (a * a * a)));
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
  const double dt = ctx.drift_factor(cell.ti_drift, ctx.ti_current);
  // The predicted velocities and energies over the drift (comoving: each with its own factor).
  const KickFactors k = ctx.comoving ? comoving_kick(ctx, static_cast<double>(cell.ti_drift), static_cast<double>(ctx.ti_current))
                                     : KickFactors{dt, dt, dt};
  // The MSPH rule reads a neighbour's sound speed in the density loop, before its ghost.
  const bool ghost_prepares =
      force_inputs == ForceInputs::UnlessGhost && !ctx.hydro.msph && cell.ti_end_min == ctx.ti_current;
  const bool prepare = force_inputs != ForceInputs::Later;
  double h_max = 0.0;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (dt != 0.0) {
      gas.x[i] += gas.v_full[i] * dt;
      if (ctx.comoving)
        gas.v[i] += gas.a_hydro[i] * k.hydro + gas.a_grav[i] * k.gravity;
      else
        gas.v[i] += (gas.a_hydro[i] + gas.a_grav[i]) * dt;
      const double u_before = gas.u[i];
      gas.u[i] = kicked_energy(ctx, u_before, gas.du_dt[i], k.energy);
      // A safety net, as in the closing kick: the prediction never takes u below half of
      // the smaller of its value and the cooling floor, whatever changed the particle mid-step.
      if (ctx.cooling)
        gas.u[i] = std::max(gas.u[i], 0.5 * std::min(u_before, ctx.expansion.code_energy(ctx.cooling->floor_energy())));
      // The prediction keeps to the floor the ghost holds (hydro.h_min_ratio).
      gas.h[i] = std::max(gas.h[i] * bounded_exp(gas.div_v[i] * dt / 3.0), ctx.hydro.h_min);
      gas.rho[i] *= bounded_exp(-gas.div_v[i] * dt);
    }
    gas.rho_msph[i] = gas.rho[i];
    gas.h_msph[i] = gas.h[i];
    if (prepare && (!ghost_prepares || !ctx.is_active(i))) hydro::prepare_force(gas, i, ctx.hydro, ctx.expansion.hubble_flow);
    h_max = std::max(h_max, gas.h[i]);
  }
  if (dt != 0.0 && (!ctx.halo_mode || ctx.owns_leaf(c))) {
    CollisionlessParticles& dm = ctx.dm;
    for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
      dm.x[i] += dm.v_full[i] * dt;
      dm.v[i] += dm.a_grav[i] * k.gravity;
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
  ClosingHalves closing{ctx};
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    // The force loop gave the hydro force per unit gas mass; hidden stars add inertia
    // (momentum (m + m_hidden) v is what pairs exchange).
    if (gas.mass_stars_hidden[i] > 0.0) gas.a_hydro[i] *= gas.mass[i] / gas.dynamical_mass(i);
    // Half of the step that ends now (shorter than its bin's if the particle was woken).
    const double dt = 0.5 * ctx.timeline.kick_factor(gas.ti_begin[i], ctx.ti_current);
    if (dt != 0.0) {
      // Comoving: each term with its own factor from the step's midpoint (energy: int dt / a^2).
      const KickFactors k = ctx.comoving ? closing.at(gas.ti_begin[i]) : KickFactors{dt, dt, dt};
      if (ctx.comoving) {
        gas.v_full[i] += gas.a_hydro[i] * k.hydro + particle_gravity(ctx, gas.a_grav[i], gas.a_mesh[i]) * k.gravity;
        mesh_close_kick(ctx, gas.v_full[i], gas.a_mesh[i]);
      } else {
        gas.v_full[i] += (gas.a_hydro[i] + gas.a_grav[i]) * dt;
      }
      // du_dt is now the hydro rate at the step's end (the force loop just reset it); the
      // cooling part of the step being closed was set at its start and applies to this half too.
      const double u_half = gas.u_full[i];
      double u = u_half + gas.du_dt[i] * k.energy;
      if (u < 0.5 * u_half) u = 0.5 * u_half;  // hydro alone never halves u in one kick (GADGET)
      if (ctx.cooling) {
        u += gas.du_dt_cool[i] * k.energy;
        cell.radiated -= gas.mass[i] * ctx.expansion.energy(gas.du_dt_cool[i] * k.energy);
        // A safety net only: the implicit solve ends the step near its solution (> the 1e4 K
        // energy); a hydro rate that changed sign during the step could otherwise overshoot.
        u = std::max(u, 0.5 * std::min(u_half, ctx.expansion.code_energy(ctx.cooling->floor_energy())));
      }
      gas.u_full[i] = u;
    }
    gas.v[i] = predicted_velocity(ctx, gas.v_full[i], gas.a_mesh[i]);
    gas.u[i] = gas.u_full[i];
  }
  CollisionlessParticles& dm = ctx.dm;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i)
    if (ctx.is_active_dm(i)) {
      const double kick = ctx.comoving ? closing.at(dm.ti_begin[i]).gravity
                                       : 0.5 * ctx.timeline.kick_factor(dm.ti_begin[i], ctx.ti_current);
      dm.v_full[i] += particle_gravity(ctx, dm.a_grav[i], dm.a_mesh[i]) * kick;
      mesh_close_kick(ctx, dm.v_full[i], dm.a_mesh[i]);
      dm.v[i] = predicted_velocity(ctx, dm.v_full[i], dm.a_mesh[i]);
    }
}

void timestep(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(c);
  const HydroParams& p = ctx.hydro;
  int max_bin = std::min(ctx.comoving ? bin_of(ctx, ctx.integration.dt_max) : ctx.timeline.bin_for(ctx.integration.dt_max),
                         TimeLine::largest_aligned_bin(ctx.ti_current));
  if (ctx.mesh_step.active()) max_bin = std::min(max_bin, ctx.mesh_step.bin);
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
      double dt = courant_dt(ctx, i, gas.v_sig[i]);
      if (ctx.gravity.enabled)
        dt = std::min(dt, ctx.comoving ? physical_gravity_timestep(ctx, ctx.softening_gas(), gas.a_grav[i], gas.a_hydro[i])
                                       : gravity_timestep(ctx.gravity, ctx.gravity.softening_gas, gas.a_hydro[i] + gas.a_grav[i]));
      if (dt < ctx.integration.dt_min)
        throw InputError(fmt::format("gas particle id {} needs a timestep {} below dt_min = {} at t = {} (h = {}, "
                                     "c = {}, |v| = {}, div v = {}, v_sig = {}, |a_hydro| = {}, |a_grav| = {})",
                                     gas.id[i], dt, ctx.integration.dt_min, ctx.timeline.time(ctx.ti_current),
                                     gas.h[i], cs, norm(gas.v[i]), gas.div_v[i], gas.v_sig[i], norm(gas.a_hydro[i]),
                                     norm(gas.a_grav[i])));
      int bin = std::min(ctx.comoving ? gas_bin_of(ctx, dt) : ctx.timeline.bin_for(dt), max_bin);
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
      const double dt = ctx.comoving ? physical_gravity_timestep(ctx, ctx.softening_of(i), dm.a_grav[i], Vec3{})
                                     : gravity_timestep(ctx.gravity, ctx.softening_of(i), dm.a_grav[i]);
      if (dt < ctx.integration.dt_min)
        throw InputError(fmt::format("{} particle id {} needs a timestep {} below dt_min = {} at t = {}",
                                     species_name(dm.species[i]), dm.id[i], dt, ctx.integration.dt_min, ctx.timeline.time(ctx.ti_current)));
      // Without gravity (stars spawned in a hydro-only run) nothing limits the step but dt_max.
      const double dt_rms = dm.species[i] == Species::DarkMatter ? ctx.dt_rms_dark_matter : ctx.dt_rms_gas;
      const int bin = ctx.comoving ? std::min(bin_of(ctx, std::min(dt, dt_rms)), max_bin)
                                   : (std::isfinite(dt) ? std::min(ctx.timeline.bin_for(dt), max_bin) : max_bin);
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
  OpeningHalves opening{ctx};
  double v_max = 0.0;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (ctx.is_active(i)) {
      if (ctx.comoving) {
        const KickFactors k = opening.at(gas.time_bin[i]);
        gas.v_full[i] += gas.a_hydro[i] * k.hydro + particle_gravity(ctx, gas.a_grav[i], gas.a_mesh[i]) * k.gravity;
        mesh_open_kick(ctx, gas.v_full[i], gas.a_mesh[i]);
        gas.u_full[i] = kicked_energy(ctx, gas.u_full[i], gas.du_dt[i], k.energy);
        cell.radiated -= gas.mass[i] * ctx.expansion.energy(gas.du_dt_cool[i] * k.energy);
      } else {
        const double dt = 0.5 * ctx.timeline.step(gas.time_bin[i]);
        gas.v_full[i] += (gas.a_hydro[i] + gas.a_grav[i]) * dt;
        gas.u_full[i] = kicked_energy(ctx, gas.u_full[i], gas.du_dt[i], dt);
        cell.radiated -= gas.mass[i] * gas.du_dt_cool[i] * dt;
      }
    }
    v_max = std::max(v_max, norm(gas.v_full[i]));
  }
  cell.v_max = v_max;
  CollisionlessParticles& dm = ctx.dm;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i)
    if (ctx.is_active_dm(i)) {
      dm.v_full[i] += particle_gravity(ctx, dm.a_grav[i], dm.a_mesh[i]) *
                      (ctx.comoving ? opening.at(dm.time_bin[i]).gravity : 0.5 * ctx.timeline.step(dm.time_bin[i]));
      mesh_open_kick(ctx, dm.v_full[i], dm.a_mesh[i]);
    }
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
    if (ctx.comoving) {
      // From the new step's midpoint to the old one's.
      const double begin = static_cast<double>(gas.ti_begin[i]);
      const KickFactors k = comoving_kick(ctx, 0.5 * (begin + static_cast<double>(new_end)),
                                          0.5 * (begin + static_cast<double>(old_end)));
      gas.v_full[i] -= gas.a_hydro[i] * k.hydro + particle_gravity(ctx, gas.a_grav[i], gas.a_mesh[i]) * k.gravity;
      gas.u_full[i] -= gas.du_dt[i] * k.energy;
      cell.radiated += gas.mass[i] * ctx.expansion.energy(gas.du_dt_cool[i] * k.energy);
    } else {
      const double undo = 0.5 * ctx.timeline.kick_factor(new_end, old_end);
      gas.v_full[i] -= (gas.a_hydro[i] + gas.a_grav[i]) * undo;
      gas.u_full[i] -= gas.du_dt[i] * undo;
      cell.radiated += gas.mass[i] * gas.du_dt_cool[i] * undo;
    }
    gas.time_bin[i] = static_cast<TimeBin>(w);
    cell.ti_end_min = std::min(cell.ti_end_min, new_end);
  }
}

}  // namespace integration
}  // namespace fountain
