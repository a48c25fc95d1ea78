#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/CellBlocks.hpp"

namespace fountain::hydro {

namespace {


// Adds to the sums of the active particles of `a` the contributions of the particles in
// `block` (positions already relative-ready: plain differences are the nearest images).
void density_sums(StepContext& ctx, const Cell& a, const NeighbourBlock& block) {
  GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  for_each_active_group(ctx, a, block, false, [&](std::size_t i, NeighbourBlock& near) {
    const Vec3 xi = gas.x[i];
    const Vec3 vi = gas.v[i];
    const double hi = gas.h[i];
    const MsphState si = msph_state(gas, i);
    DensityLanes lanes;
    DensityPairs q;
    int l = 0;
    const std::size_t n = near.within(xi, hi * hi, false);
    for (std::size_t m = 0; m < n; ++m) {
      const std::size_t k = near.hit[m];
      const std::size_t j = near.index[k];
      const Vec3 dx{xi.x - near.x[k], xi.y - near.y[k], xi.z - near.z[k]};
      const Vec3 dv = vi - gas.v[j];
      if (p.msph && j != i && msph_decoupled(si, msph_state(gas, j), dx, dv, near.r2[k], p)) continue;
      q.dx[l] = dx.x, q.dy[l] = dx.y, q.dz[l] = dx.z, q.r2[l] = near.r2[k];
      q.dvx[l] = dv.x, q.dvy[l] = dv.y, q.dvz[l] = dv.z, q.m[l] = gas.mass[j];
      if (++l == kLanes) {
        iact_density_lanes(q, hi, lanes);
        l = 0;
      }
    }
    if (l > 0) {
      for (; l < kLanes; ++l) q.dx[l] = q.dy[l] = q.dz[l] = q.dvx[l] = q.dvy[l] = q.dvz[l] = q.m[l] = 0.0, q.r2[l] = hi * hi;
      iact_density_lanes(q, hi, lanes);
    }
    const DensitySums s = lanes.total();
    gas.rho[i] += s.rho;
    gas.wcount[i] += s.w;
    gas.wcount_dh[i] += s.w_dh;
    gas.div_v[i] += s.div;
    gas.curl_v[i] += s.curl;
  });
}

}  // namespace

void density(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  const Cell& c = ctx.space.cell(ci);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.rho[i] = gas.wcount[i] = gas.wcount_dh[i] = gas.div_v[i] = 0.0;
    gas.curl_v[i] = {};
  }
  thread_local NeighbourBlock block;
  if (load_neighbourhood(ctx, ci, false, block)) density_sums(ctx, c, block);
}

}  // namespace fountain::hydro
