#include "feedback/FeedbackLoop.hpp"

#include <algorithm>
#include <cmath>

#include "hydro/HydroLoops.hpp"
#include "hydro/Kernel.hpp"
#include "hydro/MassTransfer.hpp"
#include "space/NeighbourSearch.hpp"

namespace fountain::feedback {

void deposit(StepContext& ctx, const FeedbackState& fb, std::size_t i, double dm, CellFeedback& cf) {
  GasParticles& gas = ctx.gas;
  // Energies are physical; a heating du is a^2 du in u' (docs/physics.md §11).
  const FeedbackShares e = split_feedback(fb.energy_per_mass * dm, fb.params.eps_cold, fb.params.eps_hot);
  gas.u_full[i] += ctx.expansion.code_energy(e.own / gas.mass[i]);
  gas.u[i] = gas.u_full[i];
  gas.reservoir[i] += e.reservoir;
  gas.feedback_hot_energy[i] = e.hot;
  cf.tally.energy_own += e.own;
  cf.tally.energy_reservoir += e.reservoir;
  cf.tally.energy_hot += e.hot;
}

void list_site(const FeedbackState& fb, const GasParticles& gas, std::size_t i, CellFeedback& cf) {
  if (fb.params.has_sites() && (gas.feedback_hot_energy[i] > 0.0 || gas.reservoir[i] > 0.0))
    cf.sites.push_back({i, 0, 0, -1.0});
}

void find_hot_neighbours(StepContext& ctx, FeedbackState& fb, int c) {
  const GasParticles& gas = ctx.gas;
  CellFeedback& cf = fb.cells[static_cast<std::size_t>(c)];
  const auto k = static_cast<std::size_t>(fb.params.hot_neighbours);
  for (FeedbackSite& site : cf.sites) {
    const std::vector<std::size_t> hot =
        nearest(ctx.space, gas, gas.x[site.particle], site.particle, k, fb.params.max_search_radius,
                [&](std::size_t j) { return gas.mass[j] > 0.0 && !fb.is_cold(ctx, j); });
    site.first = cf.neighbours.size();
    site.count = hot.size();
    double t_sum = 0.0;
    for (std::size_t j : hot) {
      cf.neighbours.push_back(j);
      t_sum += fb.temperature(ctx.expansion.energy(gas.u[j]));
    }
    site.mean_hot_temperature = hot.empty() ? -1.0 : t_sum / static_cast<double>(hot.size());
  }
}

void apply_feedback(StepContext& ctx, FeedbackState& fb, const std::vector<int>& leaves) {
  GasParticles& gas = ctx.gas;
  const FeedbackParams& p = fb.params;
  for (int c : leaves) {
    CellFeedback& cf = fb.cells[static_cast<std::size_t>(c)];
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
            const double du = ctx.expansion.code_energy(e_hot / m_sum);
            gas.u[j] += du;
            gas.u_full[j] += du;
            if (ctx.hydro.timestep_limiter) gas.wake_bin[j] = std::min(gas.wake_bin[j], gas.time_bin[i]);
          }
        } else {
          const double du = ctx.expansion.code_energy(e_hot / gas.mass[i]);
          gas.u[i] += du;
          gas.u_full[i] += du;
          ++fb.step_tally.hot_without_neighbours;
        }
        gas.feedback_hot_energy[i] = 0.0;
      }
      if (gas.reservoir[i] > 0.0) {
        const double t_prom =
            promotion_temperature(fb.t_star, p.promotion_factor, p.promotion_hot_factor,
                                  site.mean_hot_temperature);
        if (ctx.expansion.energy(gas.u_full[i]) + gas.reservoir[i] / gas.mass[i] >= fb.energy_at(t_prom))
          promote(ctx, fb, i);
      }
    }
    // Sites live for one step: an inactive cell must not hand its old ones out again.
    cf.sites.clear();
    cf.neighbours.clear();
  }
}

void promote(StepContext& ctx, FeedbackState& fb, std::size_t i) {
  GasParticles& gas = ctx.gas;
  StarFormationTally& tally = fb.step_tally;
  const double du = ctx.expansion.code_energy(gas.reservoir[i] / gas.mass[i]);
  gas.u_full[i] += du;
  gas.u[i] += du;
  tally.energy_released += gas.reservoir[i];
  tally.energy_promoted += gas.reservoir[i];
  gas.reservoir[i] = 0.0;
  gas.promoted[i] = 1;
  gas.promotion_time[i] = fb.time;
  ++tally.promotions;
  // Its hidden stars stay with the cold phase: the cold neighbours within h take them.
  const double hidden = gas.mass_stars_hidden[i];
  double kinetic_to_heat = 0.0;  // a^2 the physical energy in a comoving run
  if (hidden > 0.0 &&
      hydro::share_among_neighbours(ctx.space, gas, i, 0.0, hidden, 0.0,
                                    [&](std::size_t j) { return fb.is_cold(ctx, j); }, kinetic_to_heat))
    gas.mass_stars_hidden[i] = 0.0;
  tally.kinetic_to_heat += ctx.expansion.energy(kinetic_to_heat);
  // The density from the hot phase alone: h solved again over the non-cold neighbours, so
  // the particle sees N_ngb of them (however far) and the MSPH rule reads this from now on.
  const double n_ngb = ctx.hydro.neighbours;
  const std::vector<std::size_t> hot =
      nearest(ctx.space, gas, gas.x[i], i, static_cast<std::size_t>(4.0 * n_ngb), 0.0,
              [&](std::size_t j) { return gas.mass[j] > 0.0 && !fb.is_cold(ctx, j); });
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
  // The floor of h holds here as in the ghost: a promoted particle among close hot neighbours
  // would otherwise take a kernel, and a Courant step, far below every other particle's.
  const double h = std::max(hi, ctx.hydro.h_min), h_inv = 1.0 / h;
  double rho = gas.mass[i] * kernel::value(0.0, h_inv);
  if (h <= r.back()) {
    for (std::size_t n = 0; n < hot.size(); ++n) rho += gas.mass[hot[n]] * kernel::value(r[n], h_inv);
  } else {
    // The floor reaches past the nearest 4 N_ngb: every non-cold particle within it counts.
    for_each_within(ctx.space, gas, gas.x[i], h, [&](std::size_t j, const Vec3&, double rj) {
      if (j != i && gas.mass[j] > 0.0 && !fb.is_cold(ctx, j)) rho += gas.mass[j] * kernel::value(rj, h_inv);
    });
  }
  gas.h[i] = h;
  gas.h_msph[i] = h;
  gas.rho[i] = rho;
  gas.rho_msph[i] = rho;
  hydro::prepare_force(gas, i, ctx.hydro, ctx.expansion.hubble_flow);
}

}  // namespace fountain::feedback
