#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/CellBlocks.hpp"

namespace fountain::hydro {

namespace {


// Adds to the sums of the active particles of `a` the contributions of the particles in
// `block` (positions already relative-ready: plain differences are the nearest images).
void density_sums(StepContext& ctx, const Cell& a, NeighbourBlock& block) {
  GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  const std::size_t nb = block.size();
  for (std::size_t i = a.first; i < a.first + a.count; ++i) {
    if (!ctx.is_active(i)) continue;
    const Vec3 xi = gas.x[i];
    const Vec3 vi = gas.v[i];
    const double hi = gas.h[i];
    const double hi2 = hi * hi;
    const double hi_inv = 1.0 / hi;
    const MsphState si = msph_state(gas, i);
    DensitySums s;
    block.distances_to(xi);
    for (std::size_t k = 0; k < nb; ++k) {
      const double r2 = block.r2[k];
      if (r2 >= hi2) continue;
      const Vec3 dx{xi.x - block.x[k], xi.y - block.y[k], xi.z - block.z[k]};
      const std::size_t j = block.index[k];
      const Vec3 dv = vi - gas.v[j];
      if (j != i && msph_decoupled(si, msph_state(gas, j), dx, dv, r2, p)) continue;
      iact_density(dx, dv, r2, hi_inv, gas.mass[j], s);
    }
    gas.rho[i] += s.rho;
    gas.wcount[i] += s.w;
    gas.wcount_dh[i] += s.w_dh;
    gas.div_v[i] += s.div;
    gas.curl_v[i] += s.curl;
  }
}

}  // namespace

void density_self(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  Cell& c = ctx.space.cell(ci);
  thread_local NeighbourBlock block;
  load_own_cell(ctx, c, block);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.rho[i] = gas.wcount[i] = gas.wcount_dh[i] = gas.div_v[i] = 0.0;
    gas.curl_v[i] = {};
  }
  density_sums(ctx, c, block);
}

void density_pair(StepContext& ctx, int ci, int cj) {
  const Cell& a = ctx.space.cell(ci);
  thread_local NeighbourBlock block;
  if (load_neighbours(ctx, a, ctx.space.cell(cj), false, block) && block.size() > 0) density_sums(ctx, a, block);
}

}  // namespace fountain::hydro
