// Filling neighbour blocks from cells: what the self and pair tasks of both SPH loops share.
#pragma once
#include <algorithm>

#include "engine/StepContext.hpp"
#include "hydro/NeighbourBlock.hpp"

namespace fountain::hydro {

// Loads every particle of cell `c` into `block` and records on the cell the box (and largest
// h) of its active particles, for the cell's pair tasks that follow in its chain.
inline void load_own_cell(const StepContext& ctx, Cell& c, NeighbourBlock& block) {
  block.clear();
  ActiveBox box;
  for (std::size_t i = c.first; i < c.first + c.count; ++i) {
    block.add(ctx.gas.x[i], ctx.gas.h[i], i);
    if (ctx.is_active(i)) box.add(ctx.gas.x[i], ctx.gas.h[i]);
  }
  c.active_lo = box.lo;
  c.active_hi = box.hi;
  c.active_h_max = box.empty ? -1.0 : box.h_max;
}

// Loads the particles of `b` that can reach an active particle of `a`: within the active
// particles' largest h of their box (density: gather), or within the larger of that and
// their own h (force: r < max(h_i, h_j)). Positions are stored as the periodic image
// nearest `a`'s active box. Returns false when `a` has no active particle.
inline bool load_neighbours(const StepContext& ctx, const Cell& a, const Cell& b, bool own_h_reaches,
                            NeighbourBlock& block) {
  block.clear();
  const ActiveBox box(a.active_lo, a.active_hi, a.active_h_max);
  if (box.empty) return false;
  const Vec3 centre = box.centre();
  for (std::size_t j = b.first; j < b.first + b.count; ++j) {
    const Vec3 xj = centre - ctx.space.separation(centre, ctx.gas.x[j]);
    const double reach = own_h_reaches ? std::max(box.h_max, ctx.gas.h[j]) : box.h_max;
    if (box.distance2(xj) < reach * reach) block.add(xj, ctx.gas.h[j], j);
  }
  return true;
}

}  // namespace fountain::hydro
