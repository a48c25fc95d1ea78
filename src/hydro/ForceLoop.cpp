#include <algorithm>
#include <atomic>
#include <vector>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"

namespace fountain::hydro {

namespace {

ForceState force_state(const GasParticles& gas, std::size_t i, const HydroParams& p) {
  return make_force_state(gas.v[i], gas.mass[i], gas.rho[i], gas.u[i], gas.h[i], gas.div_v[i], gas.curl_v[i], p);
}

void force_sums(StepContext& ctx, int ci, int cj) {
  GasParticles& gas = ctx.gas;
  const Cell& a = ctx.space.cell(ci);
  const Cell& b = ctx.space.cell(cj);
  const HydroParams& p = ctx.hydro;
  // The neighbours' force inputs, computed once per task.
  thread_local std::vector<ForceState> fj;
  thread_local std::vector<MsphState> mj;
  fj.resize(b.count);
  mj.resize(b.count);
  for (std::size_t k = 0; k < b.count; ++k) {
    fj[k] = force_state(gas, b.first + k, p);
    mj[k] = msph_state(gas, b.first + k, p.gamma);
  }
  for (std::size_t i = a.first; i < a.first + a.count; ++i) {
    if (!ctx.is_active(i)) continue;
    const ForceState fi = force_state(gas, i, p);
    const MsphState si = msph_state(gas, i, p.gamma);
    const Vec3 xi = gas.x[i];
    ForceSums s;
    const int my_bin = p.timestep_limiter ? ctx.courant_bin(i) : 0;
    int min_bin = kNoBin;
    for (std::size_t k = 0; k < b.count; ++k) {
      const std::size_t j = b.first + k;
      if (j == i) continue;
      const Vec3 dx = ctx.space.separation(xi, gas.x[j]);
      const double r2 = dot(dx, dx);
      const double hmax = std::max(fi.h, fj[k].h);
      if (r2 >= hmax * hmax) continue;
      if (msph_decoupled(si, mj[k], dx, fi.v - fj[k].v, r2, p)) continue;
      iact_force(fi, fj[k], dx, r2, p, s);
      if (p.timestep_limiter) {
        const int bj = gas.time_bin[j];
        min_bin = std::min(min_bin, bj);
        // Ask a slower neighbour to shorten its step; a minimum, so the order of requests
        // from different threads cannot change the outcome.
        if (bj > my_bin + 2) {
          std::atomic_ref<TimeBin> wake(gas.wake_bin[j]);
          TimeBin cur = wake.load(std::memory_order_relaxed);
          const TimeBin want = static_cast<TimeBin>(my_bin + 2);
          while (want < cur && !wake.compare_exchange_weak(cur, want, std::memory_order_relaxed)) {
          }
        }
      }
    }
    if (min_bin != kNoBin) gas.limit_bin[i] = static_cast<TimeBin>(std::min<int>(gas.limit_bin[i], min_bin + 2));
    gas.a_hydro[i] += s.a;
    gas.du_dt[i] += s.du_dt;
    gas.v_sig[i] = std::max(gas.v_sig[i], s.v_sig);
  }
}

}  // namespace

void force_self(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  const Cell& c = ctx.space.cell(ci);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.a_hydro[i] = {};
    gas.du_dt[i] = 0.0;
    gas.v_sig[i] = 0.0;
    gas.limit_bin[i] = kNoBin;
  }
  force_sums(ctx, ci, ci);
}

void force_pair(StepContext& ctx, int ci, int cj) { force_sums(ctx, ci, cj); }

}  // namespace fountain::hydro
