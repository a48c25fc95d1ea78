#include <vector>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"

namespace fountain::hydro {

MsphState msph_state(const GasParticles& gas, std::size_t i, double gamma) {
  return {gas.rho_msph[i], gas.u[i], gas.h_msph[i], std::sqrt(gamma * (gamma - 1.0) * gas.u[i])};
}

namespace {

// Adds to the sums of the active particles of ci the contributions of the particles of cj
// (cj == ci for the self task).
void density_sums(StepContext& ctx, int ci, int cj) {
  GasParticles& gas = ctx.gas;
  const Cell& a = ctx.space.cell(ci);
  const Cell& b = ctx.space.cell(cj);
  const HydroParams& p = ctx.hydro;
  for (std::size_t i = a.first; i < a.first + a.count; ++i) {
    if (!ctx.is_active(i)) continue;
    const Vec3 xi = gas.x[i];
    const Vec3 vi = gas.v[i];
    const double hi = gas.h[i];
    const double hi2 = hi * hi;
    const double hi_inv = 1.0 / hi;
    const MsphState si = msph_state(gas, i, p.gamma);
    DensitySums s;
    for (std::size_t j = b.first; j < b.first + b.count; ++j) {
      const Vec3 dx = ctx.space.separation(xi, gas.x[j]);
      const double r2 = dot(dx, dx);
      if (r2 >= hi2) continue;
      const Vec3 dv = vi - gas.v[j];
      if (j != i && msph_decoupled(si, msph_state(gas, j, p.gamma), dx, dv, r2, p)) continue;
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
  const Cell& c = ctx.space.cell(ci);
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    if (!ctx.is_active(i)) continue;
    gas.rho[i] = gas.wcount[i] = gas.wcount_dh[i] = gas.div_v[i] = 0.0;
    gas.curl_v[i] = {};
  }
  density_sums(ctx, ci, ci);
}

void density_pair(StepContext& ctx, int ci, int cj) { density_sums(ctx, ci, cj); }

}  // namespace fountain::hydro
