#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/Error.hpp"
#include "core/VectorClones.hpp"
#include "hydro/HydroIact.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/NeighbourBlock.hpp"
#include "hydro/SmoothingLengthSolve.hpp"

namespace fountain::hydro {

namespace {

// The first search radius for an unconverged h, in units of its current value.
constexpr double kFirstReach = 1.25;

// Coupled particles within `radius` of particle i, from its own cell and then the
// neighbour cells in their fixed order (so sums come out the same on every run), listed as
// pairs for the density loop's four-lane sums.
void gather_candidates(const StepContext& ctx, int ci, std::size_t i, double radius, DensityPairs& out) {
  const GasParticles& gas = ctx.gas;
  const HydroParams& p = ctx.hydro;
  const MsphState si = msph_state(gas, i);
  const double r2max = radius * radius;
  std::size_t most = ctx.space.cell(ci).count;
  for (int cj : ctx.space.neighbours(ci)) most += ctx.space.cell(cj).count;
  out.reset(most);
  auto scan = [&](int cj) {
    const Cell& b = ctx.space.cell(cj);
    // The image of particle i nearest the cell serves all of it (leaves are below a quarter
    // of a periodic box); without a wrap the shift is exactly zero.
    const Vec3 xi = gas.x[i] + (ctx.space.separation(gas.x[i], b.centre()) - (gas.x[i] - b.centre()));
    // Skip a neighbour cell whose particles, however far they drifted, are all out of reach.
    const Vec3 margin{b.dx_max, b.dx_max, b.dx_max};
    if (ActiveBox(b.lo - margin, b.lo + b.width + margin, 0.0).distance2(xi) >= r2max) return;
    for (std::size_t j = b.first; j < b.first + b.count; ++j) {
      const Vec3 dx = xi - gas.x[j];
      const double r2 = dot(dx, dx);
      if (r2 >= r2max) continue;
      const Vec3 dv = gas.v[i] - gas.v[j];
      if (j != i && msph_decoupled(si, msph_state(gas, j), dx, pair_flow(dv, dx, ctx.expansion.hubble_flow), r2, p)) continue;
      out.add(dx, dv, r2, gas.mass[j]);
    }
  };
  scan(ci);
  for (int cj : ctx.space.neighbours(ci)) scan(cj);
}

// The density sums at smoothing length h over the listed pairs (those beyond h add nothing).
FOUNTAIN_VECTOR_CLONES DensitySums sums_at(DensityPairs& pairs, double h) { return sum_density_pairs(pairs, h); }
FOUNTAIN_VECTOR_CLONES StrainRate strain_at(DensityPairs& pairs, double h) { return sum_strain_pairs(pairs, h); }

}  // namespace

void ghost(StepContext& ctx, int ci) {
  GasParticles& gas = ctx.gas;
  Cell& cell = ctx.space.cell(ci);
  const HydroParams& p = ctx.hydro;
  // Neighbours are complete within this radius of any particle of the cell.
  double h_limit = cell.r_cover - cell.dx_max - cell.dx_around;
  const bool limit_is_cover = !(p.h_max > 0.0 && p.h_max < h_limit);
  if (!limit_is_cover) h_limit = p.h_max;
  // A particle at the floor with at least its neighbour number is settled there; should the
  // cell's reach fall below the floor, the reach rules and the cells are rebuilt.
  const double h_floor = std::min(p.h_min, h_limit);
  thread_local DensityPairs cand;

  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    double h = gas.h[i];
    DensitySums s;
    s.rho = gas.rho[i];
    s.w = gas.wcount[i];
    s.w_dh = gas.wcount_dh[i];
    s.div = gas.div_v[i];
    s.curl = gas.curl_v[i];
    DensityResult res = finish_density(s, h);
    const bool at_floor = h_floor > 0.0 && h == h_floor && res.wcount >= p.neighbours - p.neighbours_tolerance;
    const bool converged =
        h <= h_limit && (at_floor || std::fabs(res.wcount - p.neighbours) <= p.neighbours_tolerance);
    if (at_floor) ctx.h_min_held.fetch_add(1, std::memory_order_relaxed);
    if (!converged) {
      // h rarely changes by much in a step: bracket it within a modest radius first, and
      // search out to the cell's reach only when that radius holds too few neighbours.
      double reach = h > 0.0 ? std::min(h_limit, kFirstReach * h) : h_limit;
      gather_candidates(ctx, ci, i, reach, cand);
      DensityResult at_limit = finish_density(sums_at(cand, reach), reach);
      if (at_limit.wcount < p.neighbours - p.neighbours_tolerance && reach < h_limit) {
        reach = h_limit;
        gather_candidates(ctx, ci, i, reach, cand);
        at_limit = finish_density(sums_at(cand, reach), reach);
      }
      if (at_limit.wcount < p.neighbours - p.neighbours_tolerance) {
        // Not enough neighbours within reach: take the reach and ask for a rebuild.
        h = h_limit;
        res = at_limit;
        if (limit_is_cover) {
          ctx.cover_exceeded = true;
          ctx.h_capped.fetch_add(1, std::memory_order_relaxed);
        } else {
          ctx.h_max_capped.fetch_add(1, std::memory_order_relaxed);  // the user's cap: reported, kept
        }
      } else {
        const SmoothingLengthSolve solved =
            solve_smoothing_length([&](double x) { return finish_density(sums_at(cand, x), x); }, h, reach, p);
        if (!solved.converged)
          throw InputError(fmt::format("smoothing length of gas particle id {} did not converge in {} iterations "
                                       "(h = {}, neighbour number {}; bracket [{}, {}] of the search radius {} "
                                       "holding {} candidates)",
                                       gas.id[i], p.max_h_iterations, solved.h, solved.density.wcount, solved.lo,
                                       solved.hi, reach, cand.n));
        h = solved.h;
        res = solved.density;
        if (h < h_floor) {
          // Held at the floor: the density is that of the floor's kernel, over more neighbours.
          if (h_floor > reach) gather_candidates(ctx, ci, i, h_floor, cand);
          h = h_floor;
          res = finish_density(sums_at(cand, h), h);
          ctx.h_min_held.fetch_add(1, std::memory_order_relaxed);
        }
      }
      // `cand` holds every coupled neighbour within the final h.
      if (p.viscosity_reconstruction) {
        const StrainRate strain = strain_at(cand, h);
        gas.strain_diagonal[i] = strain.diagonal;
        gas.strain_shear[i] = strain.shear;
      }
    }
    gas.h[i] = h;
    gas.rho[i] = res.rho;
    gas.wcount[i] = res.wcount;
    gas.wcount_dh[i] = res.wcount_dh;
    gas.div_v[i] = res.div_v;
    gas.curl_v[i] = res.curl_v;
    prepare_force(gas, i, p, ctx.expansion.hubble_flow);
    gas.courant_bin[i] = static_cast<TimeBin>(ctx.courant_bin(i));
  }
  double h_max = 0.0;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) h_max = std::max(h_max, gas.h[i]);
  cell.h_max = h_max;
}

}  // namespace fountain::hydro
