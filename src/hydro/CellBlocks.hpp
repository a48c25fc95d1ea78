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
  // Leaves are below a quarter of a periodic box, so one image shift serves the whole of b.
  const Vec3 shift = ctx.space.separation(b.centre(), a.centre()) - (b.centre() - a.centre());
  const double reach2 = box.h_max * box.h_max;
  for (std::size_t j = b.first; j < b.first + b.count; ++j) {
    const Vec3 xj = ctx.gas.x[j] + shift;
    const double hj = ctx.gas.h[j];
    const double d2 = box.distance2(xj);
    if (d2 < reach2 || (own_h_reaches && d2 < hj * hj)) block.add(xj, hj, j);
  }
  return true;
}

// Particles per group: the octree order of a leaf keeps consecutive particles close, so a group
// needs only the candidates near its own small box, not those near the whole cell.
inline constexpr std::size_t kGroupSize = 16;

// Calls update(i, near) for every active particle i of `a`, group by group, with `near`
// holding the candidates of `block` that can reach some active particle of i's group.
template <class Update>
void for_each_active_group(const StepContext& ctx, const Cell& a, const NeighbourBlock& block, bool own_h_reaches,
                           Update&& update) {
  thread_local NeighbourBlock near;
  // The candidates' box, with their largest h when it counts: groups out of its reach skip the scan.
  ActiveBox reach;
  for (std::size_t k = 0; k < block.size(); ++k) reach.add({block.x[k], block.y[k], block.z[k]}, block.h2[k]);
  const double reach_h2 = own_h_reaches ? reach.h_max : 0.0;
  const std::size_t end = a.first + a.count;
  for (std::size_t g = a.first; g < end; g += kGroupSize) {
    const std::size_t g_end = std::min(g + kGroupSize, end);
    ActiveBox box;
    for (std::size_t i = g; i < g_end; ++i)
      if (ctx.is_active(i)) box.add(ctx.gas.x[i], ctx.gas.h[i]);
    if (box.empty || box.distance2(reach) >= std::max(box.h_max * box.h_max, reach_h2)) continue;
    select_near(block, box, own_h_reaches, near);
    if (near.size() == 0) continue;
    for (std::size_t i = g; i < g_end; ++i)
      if (ctx.is_active(i)) update(i, near);
  }
}

}  // namespace fountain::hydro
