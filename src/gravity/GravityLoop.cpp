#include "gravity/GravityLoop.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "gravity/GravityParams.hpp"
#include "gravity/GravityTree.hpp"
#include "gravity/LongRangeForce.hpp"

namespace fountain::gravity {

void build_tree(StepContext& ctx) {
  const GasParticles& gas = ctx.gas;
  const CollisionlessParticles& dm = ctx.dm;
  const std::size_t n = gas.size() + dm.size();
  std::vector<Vec3> x;
  std::vector<double> m, eps;
  x.reserve(n);
  m.reserve(n);
  eps.reserve(n);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    x.push_back(gas.x[i]);
    m.push_back(gas.dynamical_mass(i));  // hidden stars pull too
    eps.push_back(ctx.softening_gas());
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    x.push_back(dm.x[i]);
    m.push_back(dm.mass[i]);
    eps.push_back(ctx.softening_of(i));
  }
  TreeConfig config;
  if (ctx.long_range) {
    config.periodic = true;
    config.box_size = ctx.long_range->mesh.box();
  }
  ctx.tree = std::make_unique<GravityTree>(x, m, eps, config);
}

void compute_long_range(StepContext& ctx) {
  if (!ctx.mesh_due()) return;  // inside a mesh step: the particles keep its force
  LongRangeForce& lr = *ctx.long_range;
  GasParticles& gas = ctx.gas;
  CollisionlessParticles& dm = ctx.dm;
  const std::size_t n = gas.size() + dm.size();
  std::vector<Vec3> x(n);
  std::vector<double> m(n);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    x[i] = gas.x[i];
    m[i] = gas.dynamical_mass(i);
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    x[gas.size() + i] = dm.x[i];
    m[gas.size() + i] = dm.mass[i];
  }
  lr.acceleration.resize(n);
  lr.potential.resize(n);
  lr.mesh.compute(x, m, lr.acceleration, lr.potential, ctx.in_task_for_each);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    gas.a_mesh[i] = lr.acceleration[i];
    gas.potential_mesh[i] = lr.potential[i];
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    dm.a_mesh[i] = lr.acceleration[gas.size() + i];
    dm.potential_mesh[i] = lr.potential[gas.size() + i];
  }
}

namespace {
// Leaves with particles due this step above this share: the whole tree is refitted.
constexpr double kPartialRefitShare = 0.25;
// The reach grid's cells per side at most.
constexpr int kReachCells = 64;

// The grid cells [first, first + count) along one axis that the interval [lo, hi] overlaps,
// periodically (all of them if it spans the box).
struct CellSpan {
  int first, count;
};
CellSpan cell_span(double lo, double hi, double cell, int cells) {
  const auto a = static_cast<long long>(std::floor(lo / cell)), b = static_cast<long long>(std::floor(hi / cell));
  if (b - a + 1 >= cells) return {0, cells};
  const long long first = ((a % cells) + cells) % cells;
  return {static_cast<int>(first), static_cast<int>(b - a + 1)};
}

// With TreePM a walk reads only nodes and particles within the cut-off of its targets, which
// lie in the active leaves, each within its box grown by how far its particles moved since
// the rebuild (at most moved_most). A piece of the tree, refitted last when its particles lay
// within its cube, has them now at most 2 moved_most from it (both positions are within
// moved_most of the rebuild's), so a piece whose cube lies farther than r_cut + 2 moved_most
// from every grown active box is never read and may stay stale (GravityTree::refit_group).
// The active boxes are marked on a grid, and a piece is kept current if its cube grown by
// that distance overlaps a marked cell: a coarser test than the distance, never a finer one.
void plan_refit_reach(StepContext& ctx) {
  StepContext::RefitReach& reach = ctx.refit_reach;
  reach.cells = 0;
  if (!ctx.long_range) return;
  const std::vector<int>& leaves = ctx.space.leaves();
  std::size_t due = 0;
  for (int c : leaves) due += ctx.space.cell(c).ti_end_min <= ctx.ti_current ? 1 : 0;
  if (static_cast<double>(due) > kPartialRefitShare * static_cast<double>(leaves.size())) return;
  const double box = ctx.long_range->mesh.box();
  const double grow = ctx.moved_most;
  // Past the rounding of any distance inside the box.
  reach.radius = ctx.long_range->mesh.split().cutoff_radius() + 2.0 * grow + 1e-9 * box;
  reach.cells = std::clamp(static_cast<int>(box / reach.radius), 1, kReachCells);
  reach.cell = box / reach.cells;
  const auto n = static_cast<std::size_t>(reach.cells);
  reach.marked.assign(n * n * n, 0);
  for (int c : leaves) {
    const Cell& cell = ctx.space.cell(c);
    if (cell.ti_end_min > ctx.ti_current) continue;
    CellSpan span[3];
    for (int k = 0; k < 3; ++k)
      span[k] = cell_span(cell.lo[k] - grow, cell.lo[k] + cell.width[k] + grow, reach.cell, reach.cells);
    for (int i = 0; i < span[0].count; ++i)
      for (int j = 0; j < span[1].count; ++j)
        for (int l = 0; l < span[2].count; ++l) {
          const auto x = static_cast<std::size_t>((span[0].first + i) % reach.cells);
          const auto y = static_cast<std::size_t>((span[1].first + j) % reach.cells);
          const auto z = static_cast<std::size_t>((span[2].first + l) % reach.cells);
          reach.marked[(x * n + y) * n + z] = 1;
        }
  }
}

// Whether a piece's cube (as its last refit left it), grown by the reach, overlaps a marked
// cell.
bool within_reach(const StepContext::RefitReach& reach, const TreeNode& piece) {
  const double extent = 0.5 * piece.side + reach.radius;
  CellSpan span[3];
  for (int k = 0; k < 3; ++k)
    span[k] = cell_span(piece.centre[k] - extent, piece.centre[k] + extent, reach.cell, reach.cells);
  const auto n = static_cast<std::size_t>(reach.cells);
  for (int i = 0; i < span[0].count; ++i)
    for (int j = 0; j < span[1].count; ++j)
      for (int l = 0; l < span[2].count; ++l) {
        const auto x = static_cast<std::size_t>((span[0].first + i) % reach.cells);
        const auto y = static_cast<std::size_t>((span[1].first + j) % reach.cells);
        const auto z = static_cast<std::size_t>((span[2].first + l) % reach.cells);
        if (reach.marked[(x * n + y) * n + z] != 0) return true;
      }
  return false;
}
}  // namespace

void plan_tree_update(StepContext& ctx) {
  using U = StepContext::TreeUpdate;
  ctx.refit_reach.cells = 0;
  if (ctx.tree_current) {
    ctx.tree_update = U::keep;
    ctx.tree_current = false;  // the next run follows moved particles
  } else {
    const bool fits = ctx.tree && !ctx.tree->loose() && ctx.tree->size() == ctx.gas.size() + ctx.dm.size();
    ctx.tree_update = fits ? U::refit : U::build;
    if (fits) plan_refit_reach(ctx);
  }
}

void refit_tree_group(StepContext& ctx, int g) {
  if (ctx.tree_update != StepContext::TreeUpdate::refit) return;
  const GasParticles& gas = ctx.gas;
  const CollisionlessParticles& dm = ctx.dm;
  const std::size_t n_gas = gas.size();
  const double eps_gas = ctx.softening_gas();
  auto fetch = [&](std::size_t i) {
    if (i < n_gas) return GravityTree::RefitSource{gas.x[i], gas.dynamical_mass(i), eps_gas};
    const std::size_t j = i - n_gas;
    return GravityTree::RefitSource{dm.x[j], dm.mass[j], ctx.softening_of(j)};
  };
  const StepContext::RefitReach& reach = ctx.refit_reach;
  if (reach.cells == 0)
    ctx.tree->refit_group(g, fetch);
  else
    ctx.tree->refit_group(g, fetch, [&](const TreeNode& piece) { return within_reach(reach, piece); });
}

void finish_tree(StepContext& ctx) {
  if (ctx.tree_update == StepContext::TreeUpdate::refit) ctx.tree->finish_refit();
  else if (ctx.tree_update == StepContext::TreeUpdate::build) build_tree(ctx);
}

namespace {
double old_acceleration(const Vec3& a) {
  const double a2 = dot(a, a);
  return a2 > 0.0 ? std::sqrt(a2) : kNoOldAcceleration;
}
}  // namespace

void walk_cell(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  CollisionlessParticles& dm = ctx.dm;
  const Cell& cell = ctx.space.cell(c);
  WalkConfig config = ctx.gravity.walk();
  const LongRangeForce* long_range = ctx.long_range.get();
  if (long_range) config.split = long_range->mesh.split();
  // The cell's active particles of both species are walked together, in groups.
  std::vector<GravityTarget> targets;
  std::vector<std::size_t> gas_targets, dm_targets;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    targets.push_back({gas.x[i], ctx.softening_gas(), old_acceleration(gas.a_grav[i]),
                       static_cast<std::int64_t>(i)});
    gas_targets.push_back(i);
  }
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
    if (!ctx.is_active_dm(i)) continue;
    targets.push_back({dm.x[i], ctx.softening_of(i), old_acceleration(dm.a_grav[i]),
                       static_cast<std::int64_t>(gas.size() + i)});
    dm_targets.push_back(i);
  }
  std::vector<GravityResult> results(targets.size());
  // More than two groups: idle threads may take some.
  const bool split = targets.size() > 2 * static_cast<std::size_t>(GravityTree::group_size(config));
  ctx.tree->accelerate(targets, config, results, split ? ctx.in_task_for_each : ForEach{});
  std::size_t k = 0;
  for (const std::size_t i : gas_targets) {
    gas.a_grav[i] = results[k].acceleration;
    gas.potential[i] = results[k++].potential;
    if (long_range) {
      gas.a_grav[i] += gas.a_mesh[i];
      gas.potential[i] += gas.potential_mesh[i];
    }
  }
  for (const std::size_t i : dm_targets) {
    dm.a_grav[i] = results[k].acceleration;
    dm.potential[i] = results[k++].potential;
    if (long_range) {
      dm.a_grav[i] += dm.a_mesh[i];
      dm.potential[i] += dm.potential_mesh[i];
    }
  }
}

}  // namespace fountain::gravity
