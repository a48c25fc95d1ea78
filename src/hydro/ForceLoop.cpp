#include <algorithm>
#include <atomic>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/CellBlocks.hpp"

namespace fountain::hydro {

void prepare_force(GasParticles& gas, std::size_t i, const HydroParams& p) {
  const ForceState s = make_force_state(gas.v[i], gas.mass[i], gas.rho[i], gas.u[i], gas.h[i], gas.div_v[i],
                                        gas.curl_v[i], p);
  gas.soundspeed[i] = s.c;
  gas.p_over_rho_a[i] = s.p_over_rho_a;
  gas.inv_rho_2ma[i] = s.inv_rho_2ma;
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

void force_sums(StepContext& ctx, const Cell& a, const NeighbourBlock& block) {
  GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  for_each_active_group(ctx, a, block, true, [&](std::size_t i, NeighbourBlock& near) {
    const ForceState fi = force_state(gas, i);
    const MsphState si = msph_state(gas, i);
    const Vec3 xi = gas.x[i];
    const int my_bin = gas.courant_bin[i];
    int min_bin = kNoBin;
    ForceLanes lanes;
    ForcePairs q;
    int l = 0;
    const std::size_t n = near.within(xi, fi.h * fi.h, true);
    for (std::size_t m = 0; m < n; ++m) {
      const std::size_t k = near.hit[m];
      const std::size_t j = near.index[k];
      if (j == i) continue;
      const Vec3 dx{xi.x - near.x[k], xi.y - near.y[k], xi.z - near.z[k]};
      const Vec3 dv = fi.v - gas.v[j];
      const double r2 = near.r2[k];
      if (p.msph && msph_decoupled(si, msph_state(gas, j), dx, dv, r2, p)) continue;
      q.dx[l] = dx.x, q.dy[l] = dx.y, q.dz[l] = dx.z, q.r2[l] = r2;
      q.dvx[l] = dv.x, q.dvy[l] = dv.y, q.dvz[l] = dv.z;
      q.m[l] = gas.mass[j], q.rho[l] = gas.rho[j], q.h[l] = gas.h[j], q.c[l] = gas.soundspeed[j];
      q.p_over_rho_a[l] = gas.p_over_rho_a[j], q.inv_rho_2ma[l] = gas.inv_rho_2ma[j], q.balsara[l] = gas.balsara[j];
      if (++l == kLanes) {
        iact_force_lanes(fi, q, p, lanes);
        l = 0;
      }
      if (p.timestep_limiter) {
        const int bj = gas.time_bin[j];
        min_bin = std::min(min_bin, bj);
        if (bj > my_bin + p.limiter_bins) request_wake(gas, j, my_bin + p.limiter_bins);
      }
    }
    if (l > 0) {
      for (; l < kLanes; ++l) {
        q.dx[l] = q.dy[l] = q.dz[l] = q.dvx[l] = q.dvy[l] = q.dvz[l] = q.m[l] = q.c[l] = 0.0;
        q.p_over_rho_a[l] = q.inv_rho_2ma[l] = q.balsara[l] = 0.0;
        q.r2[l] = q.rho[l] = q.h[l] = 1.0;
      }
      iact_force_lanes(fi, q, p, lanes);
    }
    const ForceSums s = lanes.total();
    gas.a_hydro[i] += s.a;
    gas.du_dt[i] += s.du_dt;
    if (min_bin != kNoBin) gas.limit_bin[i] = static_cast<TimeBin>(std::min<int>(gas.limit_bin[i], min_bin + p.limiter_bins));
  });
}

}  // namespace

void force(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  const Cell& c = ctx.space.cell(ci);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.a_hydro[i] = {};
    gas.du_dt[i] = 0.0;
    gas.limit_bin[i] = kNoBin;
  }
  thread_local NeighbourBlock block;
  if (load_neighbourhood(ctx, ci, true, block)) force_sums(ctx, c, block);
}

}  // namespace fountain::hydro
