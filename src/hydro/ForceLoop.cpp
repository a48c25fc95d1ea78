#include <algorithm>
#include <atomic>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/CellBlocks.hpp"

namespace fountain::hydro {

void prepare_force(GasParticles& gas, std::size_t i, const HydroParams& p) {
  const ForceState s = make_force_state(gas.v[i], gas.mass[i], gas.rho[i], gas.u[i], gas.h[i], gas.div_v[i],
                                        gas.curl_v[i], p);
  gas.pressure[i] = s.pressure;
  gas.soundspeed[i] = s.c;
  gas.rho_a[i] = s.rho_a;
  gas.rho_2ma[i] = s.rho_2ma;
  gas.balsara[i] = s.balsara;
}

namespace {

// Asks particle j to shorten its step to `bin`; a minimum, so the order of requests from
// different threads cannot change the outcome.
void request_wake(GasParticles& gas, std::size_t j, int bin) {
  std::atomic_ref<TimeBin> wake(gas.wake_bin[j]);
  TimeBin cur = wake.load(std::memory_order_relaxed);
  const TimeBin want = static_cast<TimeBin>(bin);
  while (want < cur && !wake.compare_exchange_weak(cur, want, std::memory_order_relaxed)) {
  }
}

void force_sums(StepContext& ctx, const Cell& a, NeighbourBlock& block) {
  GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  const std::size_t nb = block.size();
  for (std::size_t i = a.first; i < a.first + a.count; ++i) {
    if (!ctx.is_active(i)) continue;
    const ForceState fi = force_state(gas, i);
    const MsphState si = msph_state(gas, i);
    const Vec3 xi = gas.x[i];
    const int my_bin = gas.courant_bin[i];
    int min_bin = kNoBin;
    ForceSums s;
    const double hi2 = fi.h * fi.h;
    block.distances_to(xi);
    for (std::size_t k = 0; k < nb; ++k) {
      const double r2 = block.r2[k];
      if (r2 >= hi2 && r2 >= block.h2[k]) continue;
      const std::size_t j = block.index[k];
      if (j == i) continue;
      const Vec3 dx{xi.x - block.x[k], xi.y - block.y[k], xi.z - block.z[k]};
      const ForceState fj = force_state(gas, j);
      if (msph_decoupled(si, msph_state(gas, j), dx, fi.v - fj.v, r2, p)) continue;
      iact_force(fi, fj, dx, r2, p, s);
      if (p.timestep_limiter) {
        const int bj = gas.time_bin[j];
        min_bin = std::min(min_bin, bj);
        if (bj > my_bin + p.limiter_bins) request_wake(gas, j, my_bin + p.limiter_bins);
      }
    }
    gas.a_hydro[i] += s.a;
    gas.du_dt[i] += s.du_dt;
    if (min_bin != kNoBin) gas.limit_bin[i] = static_cast<TimeBin>(std::min<int>(gas.limit_bin[i], min_bin + p.limiter_bins));
  }
}

}  // namespace

void force_self(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  Cell& c = ctx.space.cell(ci);
  thread_local NeighbourBlock block;
  // h has changed since the density loop: the pair tasks need the box with the new h.
  load_own_cell(ctx, c, block);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.a_hydro[i] = {};
    gas.du_dt[i] = 0.0;
    gas.limit_bin[i] = kNoBin;
  }
  force_sums(ctx, c, block);
}

void force_pair(StepContext& ctx, int ci, int cj) {
  const Cell& a = ctx.space.cell(ci);
  thread_local NeighbourBlock block;
  if (load_neighbours(ctx, a, ctx.space.cell(cj), true, block) && block.size() > 0) force_sums(ctx, a, block);
}

}  // namespace fountain::hydro
