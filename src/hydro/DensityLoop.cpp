#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "core/VectorClones.hpp"
#include "hydro/CellBlocks.hpp"

namespace fountain::hydro {

namespace {


// Adds to the sums of the active particles of `a` the contributions of the particles in
// `block` (positions already relative-ready: plain differences are the nearest images).
FOUNTAIN_VECTOR_CLONES void density_sums(StepContext& ctx, const Cell& a, const NeighbourBlock& block) {
  GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  thread_local DensityPairs q;  // the pairs of one particle at a time
  for_each_active_group(ctx, a, block, false, [&](std::size_t i, NeighbourBlock& near) __attribute__((always_inline)) {
    const Vec3 xi = gas.x[i];
    const Vec3 vi = gas.v[i];
    const double hi = gas.h[i];
    const MsphState si = msph_state(gas, i);
    const std::size_t n = near.within(xi, hi * hi, false);
    q.reset(n);
    for (std::size_t m = 0; m < n; ++m) {
      const std::size_t k = near.hit[m];
      const std::size_t j = near.index[k];
      const Vec3 dx{xi.x - near.x[k], xi.y - near.y[k], xi.z - near.z[k]};
      const Vec3 dv = vi - gas.v[j];
      if (p.msph && j != i &&
          msph_decoupled(si, msph_state(gas, j), dx, pair_flow(dv, dx, ctx.expansion.hubble_flow), near.r2[k], p))
        continue;
      q.add(dx, dv, near.r2[k], gas.mass[j]);
    }
    const DensitySums s = sum_density_pairs(q, hi);
    gas.rho[i] += s.rho;
    gas.wcount[i] += s.w;
    gas.wcount_dh[i] += s.w_dh;
    gas.div_v[i] += s.div;
    gas.curl_v[i] += s.curl;
    // Finished here, at this h: the ghost works it out again for a particle whose h it changes.
    if (p.viscosity_reconstruction) {
      const StrainRate strain = sum_strain_pairs(q, hi);
      gas.strain_diagonal[i] = strain.diagonal;
      gas.strain_shear[i] = strain.shear;
    }
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
    if (ctx.hydro.viscosity_reconstruction) gas.strain_diagonal[i] = gas.strain_shear[i] = {};
  }
  thread_local NeighbourBlock block;
  if (load_neighbourhood(ctx, ci, false, block)) density_sums(ctx, c, block);
}

}  // namespace fountain::hydro
