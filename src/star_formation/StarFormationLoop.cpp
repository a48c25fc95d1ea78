#include "star_formation/StarFormationLoop.hpp"

#include <algorithm>
#include <cmath>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/Kernel.hpp"
#include "space/NeighbourSearch.hpp"

namespace fountain::star_formation {

namespace {

// The feedback phase test on u rather than T: T(u) is monotonic, so T < 2 T* is u below the
// energy of 2 T*, and the searches need no temperature solve per candidate.
bool is_cold(const StarFormationState& sf, const GasParticles& gas, std::size_t j) {
  return gas.rho[j] > 0.1 * sf.law.rho_threshold && gas.u[j] < sf.u_cold_max;
}

// Shares (dm_gas, dm_hidden, heat) of particle i among gas neighbours within h_i that pass
// `accept`, in proportion to their kernel weight W(r_ij, h_i). False if there are none.
template <class Accept>
bool share_among_neighbours(const StepContext& ctx, GasParticles& gas, std::size_t i, double dm_gas,
                            double dm_hidden, double heat, Accept accept, StarFormationTally& tally) {
  std::vector<std::pair<std::size_t, double>> to;
  double w_sum = 0.0;
  const double h_inv = 1.0 / gas.h[i];
  for_each_within(ctx.space, gas, gas.x[i], gas.h[i], [&](std::size_t j, const Vec3&, double r) {
    if (j == i || !(gas.mass[j] > 0.0) || !accept(j)) return;
    const double w = kernel::value(r, h_inv);
    if (w > 0.0) {
      to.emplace_back(j, w);
      w_sum += w;
    }
  });
  if (to.empty()) return false;
  const Vec3 v_i = gas.v[i];
  const double u_i = gas.u[i];
  for (const auto& [j, w] : to) {
    const double f = w / w_sum;
    absorb(gas, j, f * dm_gas, f * dm_hidden, v_i, u_i, f * heat, tally);
  }
  return true;
}

}  // namespace

// Gas particle j takes gas mass dm_gas and hidden stellar mass dm_hidden moving at v_src
// with specific energy u_src, plus `heat`. Mass and momentum are conserved exactly; the
// kinetic energy the inelastic merger loses becomes heat, so the total energy is too.
void absorb(GasParticles& gas, std::size_t j, double dm_gas, double dm_hidden, const Vec3& v_src, double u_src,
            double heat, StarFormationTally& tally) {
  const double m_j = gas.dynamical_mass(j), dm = dm_gas + dm_hidden;
  const Vec3 v_new = (gas.v[j] * m_j + v_src * dm) * (1.0 / (m_j + dm));
  const double lost = 0.5 * m_j * dot(gas.v[j], gas.v[j]) + 0.5 * dm * dot(v_src, v_src) -
                      0.5 * (m_j + dm) * dot(v_new, v_new);
  const double thermal = gas.mass[j] * gas.u[j] + dm_gas * u_src + heat + lost;
  gas.mass[j] += dm_gas;
  gas.mass_stars_hidden[j] += dm_hidden;
  const double u_new = thermal / gas.mass[j];
  if (u_new >= gas.u[j]) {
    // Heated: the predicted and the integrated state move together.
    const double du = u_new - gas.u[j];
    gas.u[j] += du;
    gas.u_full[j] += du;
  } else {
    // Cooled by mixing with colder gas, part-way through its step: scale the integrated
    // energy and the cooling rate with the predicted energy. Subtracting instead could take
    // the integrated energy, or the energy the rest of the step cools to, below zero (the
    // cooling task's implicit rate was solved from the old energy).
    const double f = u_new / gas.u[j];
    gas.u[j] = u_new;
    gas.u_full[j] *= f;
    gas.du_dt[j] += (f - 1.0) * gas.du_dt_cool[j];
    gas.du_dt_cool[j] *= f;
  }
  const Vec3 dv = v_new - gas.v[j];
  gas.v[j] += dv;
  gas.v_full[j] += dv;
  tally.kinetic_to_heat += lost;
}

void form_stars(StepContext& ctx, StarFormationState& sf, int c) {
  GasParticles& gas = ctx.gas;
  const Cell& cell = ctx.space.cell(c);
  CellFeedback& cf = sf.cells[static_cast<std::size_t>(c)];
  cf.sites.clear();
  cf.neighbours.clear();
  const bool feedback_sites = sf.params.eps_hot > 0.0 || sf.params.eps_cold > 0.0;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.feedback_hot_energy[i] = 0.0;
    const double dt = ctx.timeline.step(gas.time_bin[i]);
    const GasState s{gas.div_v[i], gas.rho[i], gas.h[i], hydro::sound_speed(gas.rho[i], gas.u[i], ctx.hydro.gamma),
                     sf.temperature(gas.u[i])};
    if (dt > 0.0 && sf.law.check(s) == Eligibility::Eligible) {
      const double dm = sf.law.mass_formed(gas.mass[i], gas.rho[i], dt);
      gas.mass[i] -= dm;
      gas.mass_stars_hidden[i] += dm;
      cf.tally.mass_formed += dm;
      cf.tally.thermal_locked += dm * gas.u_full[i];
      const FeedbackShares e = split_feedback(sf.energy_per_mass * dm, sf.params.eps_cold, sf.params.eps_hot);
      gas.u_full[i] += e.own / gas.mass[i];
      gas.u[i] = gas.u_full[i];
      gas.reservoir[i] += e.reservoir;
      gas.feedback_hot_energy[i] = e.hot;
      cf.tally.energy_own += e.own;
      cf.tally.energy_reservoir += e.reservoir;
      cf.tally.energy_hot += e.hot;
    }
    if (feedback_sites && (gas.feedback_hot_energy[i] > 0.0 || gas.reservoir[i] > 0.0))
      cf.sites.push_back({i, 0, 0, -1.0});
  }
}

void find_hot_neighbours(StepContext& ctx, StarFormationState& sf, int c) {
  const GasParticles& gas = ctx.gas;
  CellFeedback& cf = sf.cells[static_cast<std::size_t>(c)];
  const auto k = static_cast<std::size_t>(sf.params.hot_neighbours);
  for (FeedbackSite& site : cf.sites) {
    const std::vector<std::size_t> hot =
        nearest(ctx.space, gas, gas.x[site.particle], site.particle, k, sf.params.max_search_radius,
                [&](std::size_t j) { return gas.mass[j] > 0.0 && !is_cold(sf, gas, j); });
    site.first = cf.neighbours.size();
    site.count = hot.size();
    double t_sum = 0.0;
    for (std::size_t j : hot) {
      cf.neighbours.push_back(j);
      t_sum += sf.temperature(gas.u[j]);
    }
    site.mean_hot_temperature = hot.empty() ? -1.0 : t_sum / static_cast<double>(hot.size());
  }
}

void apply_feedback(StepContext& ctx, StarFormationState& sf, const std::vector<int>& leaves) {
  GasParticles& gas = ctx.gas;
  const StarFormationParams& p = sf.params;
  for (int c : leaves) {
    CellFeedback& cf = sf.cells[static_cast<std::size_t>(c)];
    for (const FeedbackSite& site : cf.sites) {
      const std::size_t i = site.particle;
      const double e_hot = gas.feedback_hot_energy[i];
      if (e_hot > 0.0) {
        if (site.count > 0) {
          double m_sum = 0.0;
          for (std::size_t n = 0; n < site.count; ++n) m_sum += gas.mass[cf.neighbours[site.first + n]];
          for (std::size_t n = 0; n < site.count; ++n) {
            const std::size_t j = cf.neighbours[site.first + n];
            // Energy in proportion to mass: every hot neighbour gets the same du.
            const double du = e_hot / m_sum;
            gas.u[j] += du;
            gas.u_full[j] += du;
            if (ctx.hydro.timestep_limiter) gas.wake_bin[j] = std::min(gas.wake_bin[j], gas.time_bin[i]);
          }
        } else {
          gas.u[i] += e_hot / gas.mass[i];
          gas.u_full[i] += e_hot / gas.mass[i];
          ++sf.step_tally.hot_without_neighbours;
        }
        gas.feedback_hot_energy[i] = 0.0;
      }
      if (gas.reservoir[i] > 0.0) {
        const double t_prom =
            promotion_temperature(p.temperature_threshold, p.promotion_factor, p.promotion_hot_factor,
                                  site.mean_hot_temperature);
        if (gas.u_full[i] + gas.reservoir[i] / gas.mass[i] >= sf.energy_at(t_prom)) promote(ctx, sf, i);
      }
    }
    // Sites live for one step: an inactive cell must not hand its old ones out again.
    cf.sites.clear();
    cf.neighbours.clear();
  }
}

void promote(StepContext& ctx, StarFormationState& sf, std::size_t i) {
  GasParticles& gas = ctx.gas;
  StarFormationTally& tally = sf.step_tally;
  const double du = gas.reservoir[i] / gas.mass[i];
  gas.u_full[i] += du;
  gas.u[i] += du;
  tally.energy_released += gas.reservoir[i];
  gas.reservoir[i] = 0.0;
  gas.promoted[i] = 1;
  gas.promotion_time[i] = sf.time;
  ++tally.promotions;
  // Its hidden stars stay with the cold phase: the cold neighbours within h take them.
  const double hidden = gas.mass_stars_hidden[i];
  if (hidden > 0.0 &&
      share_among_neighbours(ctx, gas, i, 0.0, hidden, 0.0, [&](std::size_t j) { return is_cold(sf, gas, j); }, tally))
    gas.mass_stars_hidden[i] = 0.0;
  // The density from the hot phase alone: h solved again over the non-cold neighbours, so
  // the particle sees N_ngb of them (however far) and the MSPH rule reads this from now on.
  const double n_ngb = ctx.hydro.neighbours;
  const std::vector<std::size_t> hot =
      nearest(ctx.space, gas, gas.x[i], i, static_cast<std::size_t>(4.0 * n_ngb), 0.0,
              [&](std::size_t j) { return gas.mass[j] > 0.0 && !is_cold(sf, gas, j); });
  if (hot.empty()) return;  // nothing but cold gas anywhere: keep the density it has
  std::vector<double> r(hot.size());
  for (std::size_t n = 0; n < hot.size(); ++n) r[n] = norm(ctx.space.separation(gas.x[hot[n]], gas.x[i]));
  auto weighted_count = [&](double h) {
    const double h_inv = 1.0 / h;
    double sum = kernel::value(0.0, h_inv);
    for (double rn : r) sum += kernel::value(rn, h_inv);
    return kernel::volume_factor * h * h * h * sum;
  };
  // Bisection on h between a radius holding none of them and one holding all.
  double lo = 0.5 * r.front(), hi = std::max(r.back(), 1e-30);
  if (weighted_count(hi) < n_ngb) lo = hi;  // fewer than N_ngb hot particles in reach: use them all
  for (int it = 0; it < 100 && hi - lo > 1e-12 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (weighted_count(mid) < n_ngb ? lo : hi) = mid;
  }
  const double h = hi, h_inv = 1.0 / h;
  double rho = gas.mass[i] * kernel::value(0.0, h_inv);
  for (std::size_t n = 0; n < hot.size(); ++n) rho += gas.mass[hot[n]] * kernel::value(r[n], h_inv);
  gas.h[i] = h;
  gas.h_msph[i] = h;
  gas.rho[i] = rho;
  gas.rho_msph[i] = rho;
  hydro::prepare_force(gas, i, ctx.hydro);
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
      stars.potential[s] = gas.potential[i];
      stars.time_bin[s] = gas.time_bin[i];
      stars.ti_begin[s] = gas.ti_begin[i];
      gas.mass_stars_hidden[i] = 0.0;
      ++tally.stars_spawned;
      changed = true;
    }
    if (gas.mass[i] <= p.dissolve_fraction * m0 * (1.0 + 1e-12)) {
      const bool shared = share_among_neighbours(ctx, gas, i, gas.mass[i], gas.mass_stars_hidden[i],
                                                 gas.reservoir[i], [](std::size_t) { return true; }, tally);
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
