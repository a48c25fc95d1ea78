#include "gravity/GravityLoop.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "gravity/GravityParams.hpp"
#include "gravity/GravityTree.hpp"
#include "gravity/LongRangeForce.hpp"
#include "gravity/TreeAcrossRanks.hpp"

namespace fountain::gravity {

namespace {
TreeConfig tree_config(const StepContext& ctx) {
  TreeConfig config;
  if (ctx.long_range) {
    config.periodic = true;
    config.box_size = ctx.long_range->mesh.box();
    config.fit_cubes = true;
  }
  return config;
}

WalkConfig walk_config(const StepContext& ctx) {
  WalkConfig config = ctx.gravity.walk();
  if (ctx.long_range) config.split = ctx.long_range->mesh.split();
  return config;
}

double old_acceleration(const StepContext& ctx, const Vec3& a) {
  return ctx.first_forces ? kNoOldAcceleration : norm(a);
}

// Leaf c's active particles of both species, as the walk takes them (walked together, in
// groups), with their indices in the particle arrays.
struct LeafTargets {
  std::vector<GravityTarget> targets;
  std::vector<std::size_t> gas, dm;
};
void leaf_targets(const StepContext& ctx, int c, LeafTargets& out) {
  const GasParticles& gas = ctx.gas;
  const CollisionlessParticles& dm = ctx.dm;
  const Cell& cell = ctx.space.cell(c);
  out.targets.clear();
  out.gas.clear();
  out.dm.clear();
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
    if (!ctx.is_active(i)) continue;
    out.targets.push_back({gas.x[i], ctx.softening_gas(), old_acceleration(ctx, gas.a_grav[i]), static_cast<std::int64_t>(i)});
    out.gas.push_back(i);
  }
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
    if (!ctx.is_active_dm(i)) continue;
    out.targets.push_back({dm.x[i], ctx.softening_of(i), old_acceleration(ctx, dm.a_grav[i]),
                           static_cast<std::int64_t>(gas.size() + i)});
    out.dm.push_back(i);
  }
}

// This rank's sources across ranks: the particles of the leaves it owns, gas and then dark
// matter, each in the run's order, named by their index in this rank's arrays (as the walks'
// targets name them: gas i as i, collisionless j as the gas count + j). Where the arrays hold
// only some leaves (halo mode) a particle's place in the run is its leaf's place plus its
// offset in the leaf; otherwise its index. The order is found at each build and kept in the
// context for the refits (particles keep their places in the arrays until the next rebuild),
// so a refit only gathers the present positions, masses and softenings.
void order_own_sources(StepContext& ctx) {
  const std::size_t n_gas = ctx.gas.size();
  std::vector<std::pair<std::uint64_t, std::size_t>> g;  // (place, index)
  std::vector<std::pair<std::uint64_t, std::size_t>> d;  // (place among the collisionless, index)
  for (const int c : ctx.space.leaves()) {
    if (!ctx.owns_leaf(c)) continue;
    const Cell& cell = ctx.space.cell(c);
    const std::size_t first = ctx.leaf_places ? (*ctx.leaf_places)[static_cast<std::size_t>(c)] : cell.first;
    for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) g.emplace_back(first + (i - cell.first), i);
    const std::size_t dm_first = ctx.leaf_dm_places ? (*ctx.leaf_dm_places)[static_cast<std::size_t>(c)] : cell.dm_first;
    for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) d.emplace_back(dm_first + (i - cell.dm_first), i);
  }
  std::sort(g.begin(), g.end());
  std::sort(d.begin(), d.end());
  const std::size_t gas_total = ctx.gas_total ? *ctx.gas_total : n_gas;
  StepContext::OwnSourceOrder& order = ctx.own_source_order;
  order = {};
  order.gas = g.size();
  order.gas_arrays = n_gas;
  order.dm_arrays = ctx.dm.size();
  order.names.reserve(g.size() + d.size());
  order.places.reserve(g.size() + d.size());
  for (const auto& [place, i] : g) {
    order.places.push_back(place);
    order.names.push_back(static_cast<std::int32_t>(i));
  }
  for (const auto& [place, i] : d) {
    order.places.push_back(gas_total + place);
    order.names.push_back(static_cast<std::int32_t>(n_gas + i));
  }
}

RankSources own_sources(const StepContext& ctx) {
  const StepContext::OwnSourceOrder& order = ctx.own_source_order;
  RankSources s;
  s.count = order.names.size();
  s.source = [&ctx, &order](std::size_t k) {
    const auto i = static_cast<std::size_t>(order.names[k]);
    if (k < order.gas) return RankSources::Source{ctx.gas.x[i], ctx.gas.dynamical_mass(i), ctx.softening_gas()};
    const std::size_t j = i - order.gas_arrays;
    return RankSources::Source{ctx.dm.x[j], ctx.dm.mass[j], ctx.softening_of(j)};
  };
  s.places = order.places;
  s.names = order.names;
  return s;
}
}  // namespace

const GravityTree& walk_tree(const StepContext& ctx) {
  return ctx.tree_across ? ctx.tree_across->last_tree() : *ctx.tree;
}

void build_tree(StepContext& ctx) {
  if (ctx.tree_messages) {
    ctx.tree_across.reset();  // not beside the new one
    order_own_sources(ctx);
    ctx.tree_across = std::make_unique<TreeAcrossRanks>(*ctx.tree_messages, own_sources(ctx), tree_config(ctx), walk_config(ctx));
    ctx.tree.reset();  // assembled for each step's walks (finish_tree)
    return;
  }
  ctx.tree.reset();  // not beside the new one
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
  ctx.tree = std::make_unique<GravityTree>(x, m, eps, tree_config(ctx));
}

void compute_long_range(StepContext& ctx) {
  if (!ctx.mesh_due()) return;  // inside a mesh step: the particles keep its force
  LongRangeForce& lr = *ctx.long_range;
  GasParticles& gas = ctx.gas;
  CollisionlessParticles& dm = ctx.dm;
  // The particles this rank feeds the mesh: every one, or in halo mode those of the leaves it
  // owns, whose forces come back to it (the holders of a leaf receive its gas's with the
  // step's other changes).
  std::vector<std::size_t> g, d;
  if (ctx.halo_mode) {
    std::size_t n_gas = 0, n_dm = 0;
    for (const int c : ctx.space.leaves()) {
      if (!ctx.owns_leaf(c)) continue;
      n_gas += ctx.space.cell(c).count;
      n_dm += ctx.space.cell(c).dm_count;
    }
    g.reserve(n_gas);
    d.reserve(n_dm);
    for (const int c : ctx.space.leaves()) {
      if (!ctx.owns_leaf(c)) continue;
      const Cell& cell = ctx.space.cell(c);
      for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) g.push_back(i);
      for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) d.push_back(i);
    }
  } else {
    g.resize(gas.size());
    d.resize(dm.size());
    std::iota(g.begin(), g.end(), std::size_t{0});
    std::iota(d.begin(), d.end(), std::size_t{0});
  }
  const std::size_t n_gas = g.size(), n = g.size() + d.size();
  // The results go into the particles' fields at once: nothing of this is kept between
  // mesh steps.
  auto store = [&](std::size_t k, const Vec3& a, double phi) {
    if (k < n_gas) {
      gas.a_mesh[g[k]] = a;
      gas.potential_mesh[g[k]] = phi;
    } else {
      dm.a_mesh[d[k - n_gas]] = a;
      dm.potential_mesh[d[k - n_gas]] = phi;
    }
  };
  if (ctx.halo_mode) {
    // Read where they lie: copies of positions and masses would add 32 bytes a particle to
    // the peak of a mesh step.
    const gravity::PeriodicMesh::Sources sources{
        n, [&](std::size_t k) { return k < n_gas ? gas.x[g[k]] : dm.x[d[k - n_gas]]; },
        [&](std::size_t k) { return k < n_gas ? gas.dynamical_mass(g[k]) : dm.mass[d[k - n_gas]]; }};
    lr.mesh.compute_owned(sources, store, ctx.in_task_for_each);
    return;
  }
  std::vector<Vec3> x(n);
  std::vector<double> m(n);
  for (std::size_t k = 0; k < n; ++k) {
    x[k] = k < n_gas ? gas.x[g[k]] : dm.x[d[k - n_gas]];
    m[k] = k < n_gas ? gas.dynamical_mass(g[k]) : dm.mass[d[k - n_gas]];
  }
  std::vector<Vec3> acceleration(n);
  std::vector<double> potential(n);
  lr.mesh.compute(x, m, acceleration, potential, ctx.in_task_for_each);
  for (std::size_t k = 0; k < n; ++k) store(k, acceleration[k], potential[k]);
}

void plan_tree_update(StepContext& ctx) {
  using U = StepContext::TreeUpdate;
  if (ctx.tree_current) {
    ctx.tree_update = U::keep;
    ctx.tree_current = false;  // the next run follows moved particles
  } else if (ctx.tree_messages) {
    ctx.tree_update = ctx.tree_across && !ctx.tree_across->loose() ? U::refit : U::build;
  } else {
    const bool fits = ctx.tree && !ctx.tree->loose() && ctx.tree->size() == ctx.gas.size() + ctx.dm.size();
    ctx.tree_update = fits ? U::refit : U::build;
  }
}

void refit_tree_group(StepContext& ctx, int g) {
  if (ctx.tree_update != StepContext::TreeUpdate::refit || ctx.tree_messages) return;
  const GasParticles& gas = ctx.gas;
  const CollisionlessParticles& dm = ctx.dm;
  const std::size_t n_gas = gas.size();
  const double eps_gas = ctx.softening_gas();
  ctx.tree->refit_group(g, [&](std::size_t i) {
    if (i < n_gas) return GravityTree::RefitSource{gas.x[i], gas.dynamical_mass(i), eps_gas};
    const std::size_t j = i - n_gas;
    return GravityTree::RefitSource{dm.x[j], dm.mass[j], ctx.softening_of(j)};
  });
}

void finish_tree(StepContext& ctx) {
  if (ctx.tree_messages) {
    // Across ranks: this rank's subtrees refitted (or all built anew), then the tree for the
    // step's walks of its own leaves' active particles, assembled with what the other ranks
    // send for them (every step: the walks and the moments change).
    if (ctx.tree_update == StepContext::TreeUpdate::refit) {
      // The kept order stands while the arrays do (a spawned star or a removed particle brings
      // a rebuild first; should one not, the order is found anew and the refit reports the
      // changed count).
      const StepContext::OwnSourceOrder& order = ctx.own_source_order;
      if (order.gas_arrays != ctx.gas.size() || order.dm_arrays != ctx.dm.size()) order_own_sources(ctx);
      ctx.tree_across->refit(*ctx.tree_messages, own_sources(ctx));
    } else if (ctx.tree_update == StepContext::TreeUpdate::build) {
      build_tree(ctx);
    }
    // Each leaf's targets as a batch's bounds, not held: the walks list them again.
    std::vector<TargetBatch> batches;
    LeafTargets leaf;
    for (const int c : ctx.space.leaves()) {
      if (!ctx.owns_leaf(c)) continue;
      leaf_targets(ctx, c, leaf);
      if (!leaf.targets.empty()) batches.emplace_back(leaf.targets);
    }
    ctx.tree_across->tree_for(*ctx.tree_messages, batches);  // what walk_tree() gives the walks
    return;
  }
  if (ctx.tree_update == StepContext::TreeUpdate::refit) ctx.tree->finish_refit();
  else if (ctx.tree_update == StepContext::TreeUpdate::build) build_tree(ctx);
}

void walk_cell(StepContext& ctx, int c) {
  GasParticles& gas = ctx.gas;
  CollisionlessParticles& dm = ctx.dm;
  const WalkConfig config = walk_config(ctx);
  const LongRangeForce* long_range = ctx.long_range.get();
  LeafTargets leaf;
  leaf_targets(ctx, c, leaf);
  const std::vector<GravityTarget>& targets = leaf.targets;
  const std::vector<std::size_t>& gas_targets = leaf.gas;
  const std::vector<std::size_t>& dm_targets = leaf.dm;
  std::vector<GravityResult> results(targets.size());
  // More than two groups: idle threads may take some.
  const bool split = targets.size() > 2 * static_cast<std::size_t>(GravityTree::group_size(config));
  walk_tree(ctx).accelerate(targets, config, results, split ? ctx.in_task_for_each : ForEach{});
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
