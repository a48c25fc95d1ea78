// Filling neighbour blocks from cells: what the self and pair tasks of both SPH loops share.
#pragma once
#include <algorithm>

#include "step/StepContext.hpp"
#include "hydro/NeighbourBlock.hpp"

namespace fountain::hydro {

// Loads into `block` the particles that can reach an active particle of cell `a`: all of its
// own, then those of each neighbour cell (in the fixed neighbour order, so every particle's
// sums always add up in the same order) within the active particles' largest h of their box
// (density: gather) or, when `own_h_reaches`, within the larger of that and their own h
// (force: r < max(h_i, h_j)). Positions are stored as the periodic image nearest `a`.
// Returns false when `a` has no active particle. The density loop must not read its
// neighbours' h (their ghosts may be solving it): it stores h = 0 for them.
inline bool load_neighbourhood(const StepContext& ctx, int ci, bool own_h_reaches, NeighbourBlock& block) {
  const Cell& a = ctx.space.cell(ci);
  std::size_t most = a.count;
  for (int n : ctx.space.neighbours(ci)) most += ctx.space.cell(n).count;
  block.reset(most + kScanSlack);
  ActiveBox box;
  for (std::size_t i = a.first; i < a.first + a.count; ++i)
    if (ctx.is_active(i)) box.add(ctx.gas.x[i], ctx.gas.h[i]);
  if (box.empty) return false;
  for (std::size_t i = a.first; i < a.first + a.count; ++i) block.add(ctx.gas.x[i], ctx.gas.h[i] * ctx.gas.h[i], i);
  const double reach2 = box.h_max * box.h_max;
  // Each neighbour cell is staged as plain arrays (shifted positions; h^2, or 0 where the
  // loop must not read h) and filtered by the same scan as a group's candidates.
  thread_local NeighbourBlock staged;
  for (int n : ctx.space.neighbours(ci)) {
    const Cell& b = ctx.space.cell(n);
    // Leaves are below a quarter of a periodic box, so one image shift serves the whole of b.
    const Vec3 shift = ctx.space.separation(b.centre(), a.centre()) - (b.centre() - a.centre());
    // The whole cell out of reach (its particles may have drifted dx_max out of its box)?
    const Vec3 margin{b.dx_max, b.dx_max, b.dx_max};
    const ActiveBox cell_box(b.lo + shift - margin, b.lo + b.width + shift + margin, 0.0);
    const double cell_d2 = box.distance2(cell_box);
    if (cell_d2 >= reach2 && !(own_h_reaches && cell_d2 < b.h_max * b.h_max)) continue;
    staged.reset(b.count);
    for (std::size_t j = b.first; j < b.first + b.count; ++j)
      staged.add(ctx.gas.x[j] + shift, own_h_reaches ? ctx.gas.h[j] * ctx.gas.h[j] : 0.0, j);
    block.append_near(staged.view(), staged.size(), box.lo, box.hi, reach2, own_h_reaches);
  }
  return true;
}

// Particles per group: the octree order of a leaf keeps consecutive particles close, so a group
// needs only the candidates near its own small box, not those near the whole cell.
inline constexpr std::size_t kGroupSize = 16;

// Calls update(i, near) for every active particle i of `a`, group by group, with `near`
// holding the candidates of `block` that can reach some active particle of i's group.
// Forced inline (as are the loops' per-particle bodies) so that the AVX2 clones of the loops
// that call it compile it too: a separate function would be built for plain x86-64 only.
template <class Update>
[[gnu::always_inline]] inline void for_each_active_group(const StepContext& ctx, const Cell& a,
                                                         const NeighbourBlock& block, bool own_h_reaches,
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
