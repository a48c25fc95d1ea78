#include "gravity/GravityLoop.hpp"

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

void plan_tree_update(StepContext& ctx) {
  using U = StepContext::TreeUpdate;
  if (ctx.tree_current) {
    ctx.tree_update = U::keep;
    ctx.tree_current = false;  // the next run follows moved particles
  } else {
    const bool fits = ctx.tree && !ctx.tree->loose() && ctx.tree->size() == ctx.gas.size() + ctx.dm.size();
    ctx.tree_update = fits ? U::refit : U::build;
  }
}

void refit_tree_group(StepContext& ctx, int g) {
  if (ctx.tree_update != StepContext::TreeUpdate::refit) return;
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
