#include <algorithm>
#include <atomic>
#include <cstdint>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "core/VectorClones.hpp"
#include "hydro/CellBlocks.hpp"

namespace fountain::hydro {

void prepare_force(GasParticles& gas, std::size_t i, const HydroParams& p, double hubble_flow) {
  // The Balsara switch compares physical divergence and curl: comoving, D'/a^2 + 3H and
  // |C'|/a^2 against c/h = c'/(a^2 h') (gamma = 5/3), i.e. D' + 3 a^2 H, |C'| and c'/h'.
  const double div_v = hubble_flow != 0.0 ? gas.div_v[i] + 3.0 * hubble_flow : gas.div_v[i];
  const ForceState s = make_force_state(gas.v[i], gas.mass[i], gas.rho[i], gas.u[i], gas.h[i], div_v,
                                        gas.curl_v[i], p, {gas.strain_diagonal[i], gas.strain_shear[i]});
  gas.soundspeed[i] = s.c;
  gas.p_over_rho_a[i] = s.p_over_rho_a;
  gas.inv_rho_2ma[i] = s.inv_rho_2ma;
  gas.balsara[i] = s.balsara;
  gas.entropy[i] = s.entropy;
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

// Lists the pairs of particle i with the candidates near.hit[0 .. n): one plain loop with
// every array behind a local pointer (through the thread's list the compiler reloaded each
// array's address after every store). kStrain: j's strain rates too.
template <bool kStrain>
[[gnu::always_inline]] inline void list_force_pairs(const GasParticles& gas, const NeighbourBlock& near,
                                                    const std::uint32_t* hit, std::size_t n, const Vec3& xi,
                                                    const Vec3& vi, ForcePairs& q) {
  q.reset(n, kStrain);
  double* __restrict dx = q.dx.data();
  double* __restrict dy = q.dy.data();
  double* __restrict dz = q.dz.data();
  double* __restrict r2 = q.r2.data();
  double* __restrict dvx = q.dvx.data();
  double* __restrict dvy = q.dvy.data();
  double* __restrict dvz = q.dvz.data();
  double* __restrict m = q.m.data();
  double* __restrict rho = q.rho.data();
  double* __restrict h = q.h.data();
  double* __restrict c = q.c.data();
  double* __restrict pa = q.p_over_rho_a.data();
  double* __restrict ir = q.inv_rho_2ma.data();
  double* __restrict bal = q.balsara.data();
  const double *nx = near.x.data(), *ny = near.y.data(), *nz = near.z.data(), *nr2 = near.r2.data();
  const std::size_t* index = near.index.data();
  const Vec3* v = gas.v.data();
  for (std::size_t p = 0; p < n; ++p) {
    const std::size_t k = hit[p];
    const std::size_t j = index[k];
    dx[p] = xi.x - nx[k], dy[p] = xi.y - ny[k], dz[p] = xi.z - nz[k], r2[p] = nr2[k];
    dvx[p] = vi.x - v[j].x, dvy[p] = vi.y - v[j].y, dvz[p] = vi.z - v[j].z;
    m[p] = gas.mass[j], rho[p] = gas.rho[j], h[p] = gas.h[j], c[p] = gas.soundspeed[j];
    pa[p] = gas.p_over_rho_a[j], ir[p] = gas.inv_rho_2ma[j], bal[p] = gas.balsara[j];
    if constexpr (kStrain) {
      const Vec3 &d = gas.strain_diagonal[j], &o = gas.strain_shear[j];
      q.entropy[p] = gas.entropy[j];
      q.sxx[p] = d.x, q.syy[p] = d.y, q.szz[p] = d.z, q.sxy[p] = o.x, q.sxz[p] = o.y, q.syz[p] = o.z;
    }
  }
  q.n = n;
}

// Particle i's force sums with the loop's options as template arguments.
template <bool kReconstruct>
[[gnu::always_inline]] inline ForceSums force_pair_sums(const ForceState& fi, ForcePairs& q, const HydroParams& p,
                                                        bool signal_velocity, double hubble_flow) {
  if (hubble_flow != 0.0)
    return signal_velocity ? sum_force_pairs<true, true, kReconstruct>(fi, q, p, hubble_flow)
                           : sum_force_pairs<false, true, kReconstruct>(fi, q, p, hubble_flow);
  return signal_velocity ? sum_force_pairs<true, false, kReconstruct>(fi, q, p)
                         : sum_force_pairs<false, false, kReconstruct>(fi, q, p);
}

FOUNTAIN_VECTOR_CLONES void force_sums(StepContext& ctx, const Cell& a, const NeighbourBlock& block) {
  GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  const bool msph = p.msph, limiter = p.timestep_limiter;
  const bool signal_velocity = p.courant_criterion == CourantCriterion::SignalVelocity;
  const bool reconstruct = p.viscosity_reconstruction;
  const int limiter_bins = p.limiter_bins;
  const double hubble_flow = ctx.expansion.hubble_flow;
  thread_local ForcePairs q;  // the pairs of one particle at a time
  long long decoupled = 0;    // pair forces the MSPH rule dropped: one count per cell, not per pair
  for_each_active_group(ctx, a, block, true, [&](std::size_t i, NeighbourBlock& near) __attribute__((always_inline)) {
    const ForceState fi = force_state(gas, i);
    const Vec3 xi = gas.x[i];
    const std::size_t n = near.within(xi, fi.h * fi.h, true);
    // The partners, in place in the hit list: every hit but i itself and, under MSPH, the
    // decoupled ones.
    std::uint32_t* hit = near.hit.data();
    std::size_t kept = 0;
    if (msph) {
      const MsphState si = msph_state(gas, i);
      for (std::size_t m = 0; m < n; ++m) {
        const std::size_t k = hit[m];
        const std::size_t j = near.index[k];
        if (j == i) continue;
        const Vec3 dx{xi.x - near.x[k], xi.y - near.y[k], xi.z - near.z[k]};
        if (msph_decoupled(si, msph_state(gas, j), dx, pair_flow(fi.v - gas.v[j], dx, hubble_flow), near.r2[k], p)) {
          ++decoupled;
          continue;
        }
        hit[kept++] = static_cast<std::uint32_t>(k);
      }
    } else {
      for (std::size_t m = 0; m < n; ++m) {
        const std::uint32_t k = hit[m];
        hit[kept] = k;
        kept += near.index[k] != i ? 1 : 0;
      }
    }
    ForceSums s;
    if (reconstruct) {
      list_force_pairs<true>(gas, near, hit, kept, xi, fi.v, q);
      s = force_pair_sums<true>(fi, q, p, signal_velocity, hubble_flow);
    } else {
      list_force_pairs<false>(gas, near, hit, kept, xi, fi.v, q);
      s = force_pair_sums<false>(fi, q, p, signal_velocity, hubble_flow);
    }
    gas.a_hydro[i] += s.a;
    gas.du_dt[i] += s.du_dt;
    if (signal_velocity) gas.v_sig[i] = std::max(gas.v_sig[i], s.v_sig);
    if (limiter && kept > 0) {
      const int my_bin = gas.courant_bin[i];
      int min_bin = kNoBin;
      for (std::size_t m = 0; m < kept; ++m) {
        const std::size_t j = near.index[hit[m]];
        const int bj = gas.time_bin[j];
        min_bin = std::min(min_bin, bj);
        if (bj > my_bin + limiter_bins) request_wake(gas, j, my_bin + limiter_bins);
      }
      gas.limit_bin[i] = static_cast<TimeBin>(std::min<int>(gas.limit_bin[i], min_bin + limiter_bins));
    }
  });
  if (decoupled > 0) ctx.msph_decoupled.fetch_add(decoupled, std::memory_order_relaxed);
}

}  // namespace

void force(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  const Cell& c = ctx.space.cell(ci);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.a_hydro[i] = {};
    gas.du_dt[i] = 0.0;
    gas.v_sig[i] = 2.0 * gas.soundspeed[i];  // as SWIFT: a lone particle's signal still travels
    gas.limit_bin[i] = kNoBin;
  }
  thread_local NeighbourBlock block;
  if (load_neighbourhood(ctx, ci, true, block)) force_sums(ctx, c, block);
}

}  // namespace fountain::hydro
