// The tree walk: targets in spatially compact groups share one walk and one interaction list,
// which is then evaluated for every target of the group (docs/gravity.md, "Grouped walk").
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/VectorClones.hpp"
#include "gravity/GravityTree.hpp"
#include "gravity/GravityWalkGroup.hpp"
#include "gravity/LeafScan.hpp"

namespace fountain::gravity {

namespace {
// An opened leaf whose cube lies wholly within the group's largest target spline length of
// its box has only near particles; one whose cube is wholly beyond every pair's spline length (h, the
// largest of the group's and the leaf's) only far ones. Either way each particle's own test
// would say the same, as the particles lie inside their leaf's cube (built so, and refitted
// so); `slack` keeps rounding from deciding. Otherwise each particle is tested.
enum class Bulk { near, far, mixed };
inline Bulk classify_leaf(const Vec3& box_half, double h_max, const TreeNode& leaf, double ox, double oy,
                          double oz, double d2box, double h, double slack) {
  const double half = 0.5 * leaf.side;
  const double fx = gap(ox, box_half.x - half), fy = gap(oy, box_half.y - half), fz = gap(oz, box_half.z - half);
  if (std::sqrt(fx * fx + fy * fy + fz * fz) + slack < h_max) return Bulk::near;
  if (d2box > 0.0 && std::sqrt(d2box) >= h + slack) return Bulk::far;
  return Bulk::mixed;
}
}  // namespace

void GravityTree::walk_group(const Group& g, const WalkConfig& config, InteractionList& list) const {
  list.clear();
  const WalkRules rules = walk_rules(config, nodes_[0]);
  const double cutoff = rules.cutoff, slack = rules.slack;
  // Each of a node's particles, tested alone (scan_leaf; in TreePM about half the particles of
  // an opened node lie beyond the cut-off). The particles share their node's nearest image
  // when the node's cube lies within half a box of the group's centre, less a margin for
  // rounding (always, short of a cut-off near half the box); otherwise each takes its own.
  const double cutoff2 = rules.split ? cutoff * cutoff : std::numeric_limits<double>::infinity();
  LeafScanBox scan{g.centre, g.half, {}, g.h_max, cutoff2};
  const double half_box = 0.5 * config_.box_size, margin = 1e-9 * config_.box_size;
  // What image() adds to an offset: nothing within half a box, whole boxes otherwise.
  auto shift_of = [&](double offset) {
    return !config_.periodic || std::fabs(offset) <= half_box ? 0.0 : -config_.box_size * std::nearbyint(offset / config_.box_size);
  };
  auto shared_shift = [&](const TreeNode& node, const NodeOffsets& at) {
    if (!config_.periodic) return true;
    const double reach = 0.5 * node.side + margin;
    const double images[3] = {at.ox, at.oy, at.oz};
    for (int d = 0; d < 3; ++d) {
      if (std::fabs(images[d]) + reach >= half_box) return false;
      scan.shift[d] = shift_of(node.centre[d] - g.centre[d]);
    }
    return true;
  };
  auto add_particles = [&](const TreeNode& node, const NodeOffsets& at) {
    std::int32_t far_count = static_cast<std::int32_t>(list.far.size()),
                 near_count = static_cast<std::int32_t>(list.near.size());
    list.far.resize(static_cast<std::size_t>(far_count + node.count + 8));
    list.near.resize(static_cast<std::size_t>(near_count + node.count + 8));
    if (shared_shift(node, at)) {
      scan_leaf(pos_.data(), spline_.data(), node.first, node.count, scan, list.far.data(), &far_count,
                list.near.data(), &near_count);
    } else {
      // Each particle with its own image: the same test, one particle at a time.
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        for (int d = 0; d < 3; ++d) scan.shift[d] = shift_of(pos_[k][d] - g.centre[d]);
        scan_leaf_portable(pos_.data(), spline_.data(), k, 1, scan, list.far.data(), &far_count, list.near.data(),
                           &near_count);
      }
    }
    list.far.resize(static_cast<std::size_t>(far_count));
    list.near.resize(static_cast<std::size_t>(near_count));
  };
  // All of a node's particles, decided for the whole node (Bulk::near or Bulk::far).
  auto add_whole = [&](const TreeNode& node, Bulk bulk) {
    auto& to = bulk == Bulk::far ? list.far : list.near;
    const std::size_t at = to.size();
    to.resize(at + static_cast<std::size_t>(node.count));
    std::iota(to.begin() + static_cast<std::ptrdiff_t>(at), to.end(), node.first);
  };
  std::int32_t n = 0;
  NodeOffsets o;
  while (n >= 0) {
    const TreeNode& node = nodes_[n];
    switch (decide(node, g, config, rules, o)) {
      case Visit::skip:
        n = node.next;
        break;
      case Visit::accept:
        list.nodes.push_back(n);
        n = node.next;
        break;
      case Visit::accept_softened:
        list.soft_nodes.push_back(n);
        n = node.next;
        break;
      case Visit::open:
        n = node.first_child;
        break;
      case Visit::pruned:
        throw std::logic_error("GravityTree: a walk opened node " + std::to_string(n) +
                               ", whose inside the rank that holds it did not send for this walk's targets");
      case Visit::list:
        if (rules.split) {
          // A leaf, or a small node, listed at once: whole where its farthest point lies within
          // the cut-off of the box and it is wholly near or wholly far; otherwise each particle
          // is tested.
          const double half = 0.5 * node.side;
          // The farthest a point of the node's cube lies from the box, per axis.
          const double fx = gap(o.ox, g.half.x - half), fy = gap(o.oy, g.half.y - half), fz = gap(o.oz, g.half.z - half);
          const double reach2 = fx * fx + fy * fy + fz * fz;
          const Bulk bulk = std::sqrt(reach2) + slack <= cutoff
                                ? classify_leaf(g.half, g.h_max, node, o.ox, o.oy, o.oz, o.d2box, o.h, slack)
                                : Bulk::mixed;
          if (bulk != Bulk::mixed)
            add_whole(node, bulk);
          else
            add_particles(node, o);
        } else if (const Bulk bulk = classify_leaf(g.half, g.h_max, node, o.ox, o.oy, o.oz, o.d2box, o.h, slack);
                   bulk != Bulk::mixed) {
          // Decided for the whole leaf, so its particles need no test of their own.
          add_whole(node, bulk);
        } else {
          add_particles(node, o);
        }
        n = node.next;
        break;
    }
  }
}

// Every list is evaluated in float over 8 or 16 lanes (the group padded with copies that are
// no particle), twice the lanes of double, with lengths relative to the group's centre in
// units of length_unit_ and accelerations in units of g.accel_unit (powers of two, so the
// scalings are exact, chosen so that float's exponent range holds whatever the unit
// system). Each list sums in float and is added to the double totals once per group: nodes
// and far particles, then near particles.
// Errors: ~1e-7 per interaction for nodes and far particles, up to a few 1e-6 for near pairs,
// far below the walk's ~1e-3 (docs/gravity.md).
FOUNTAIN_VECTOR_CLONES void GravityTree::evaluate_group(Group& g, const WalkConfig& config, const InteractionList& list) const {
  const int nt = g.n;
  const auto [lanes, unit_inv, gm_scale, q_scale, pot_unit] = float_units(nt, length_unit_, g.accel_unit);
  const double G = config.G;
  const bool quadrupole = config.expansion == MultipoleOrder::quadrupole;
  float ax[kGroupSize] = {}, ay[kGroupSize] = {}, az[kGroupSize] = {}, pot[kGroupSize] = {};
  // A node's centre of mass relative to the group's centre, G M and G Q, in the float units.
  struct ScaledNode {
    float cx, cy, cz, gm, q[6];
  };
  auto scaled = [&](const TreeNode& node) {
    ScaledNode n;
    n.cx = static_cast<float>((node.com.x - g.centre.x) * unit_inv);
    n.cy = static_cast<float>((node.com.y - g.centre.y) * unit_inv);
    n.cz = static_cast<float>((node.com.z - g.centre.z) * unit_inv);
    n.gm = static_cast<float>(G * node.mass * gm_scale);
    for (int i = 0; i < 6; ++i) n.q[i] = static_cast<float>(G * node.quadrupole[i] * q_scale);
    return n;
  };
  // node_field's arithmetic over the group's targets; without the branch on the expansion
  // order inside, the loop over targets vectorises.
  auto nodes = [&]<bool kQuadrupole>() {
    for (const std::int32_t k : list.nodes) {
      const auto [cx, cy, cz, gm, q] = scaled(nodes_[k]);
      for (int t = 0; t < lanes; ++t) {
        const float dx = g.xr[t] - cx, dy = g.yr[t] - cy, dz = g.zr[t] - cz;
        const float r2 = dx * dx + dy * dy + dz * dz;
        const float r_inv = 1.0f / std::sqrt(r2);
        const float r2_inv = r_inv * r_inv;
        const float r3_inv = r_inv * r2_inv;
        const float s = gm * r3_inv;
        float fx = -s * dx, fy = -s * dy, fz = -s * dz, fp = -gm * r_inv;
        if constexpr (kQuadrupole) {
          const float r5_inv = r3_inv * r2_inv;
          const float qx = q[0] * dx + q[3] * dy + q[4] * dz, qy = q[3] * dx + q[1] * dy + q[5] * dz,
                      qz = q[4] * dx + q[5] * dy + q[2] * dz;
          const float dqd = dx * qx + dy * qy + dz * qz;
          const float c = -2.5f * dqd * r2_inv;
          fx += r5_inv * (qx + c * dx);
          fy += r5_inv * (qy + c * dy);
          fz += r5_inv * (qz + c * dz);
          fp -= 0.5f * dqd * r5_inv;
        }
        ax[t] += fx;
        ay[t] += fy;
        az[t] += fz;
        pot[t] += fp;
      }
    }
  };
  if (quadrupole)
    nodes.template operator()<true>();
  else
    nodes.template operator()<false>();
  // Nodes within some target's softening: softened_node_field's arithmetic, each target with
  // its own pair spline length (the larger of its own and the node's).
  for (const std::int32_t k : list.soft_nodes) {
    const TreeNode& node = nodes_[k];
    const auto [cx, cy, cz, gm, q] = scaled(node);
    const float trace = static_cast<float>(G * node.second_moment * q_scale);
    const float h_node = static_cast<float>(spline_length(node.max_softening) * unit_inv);
    const float h_node_inv = 1.0f / h_node;
    for (int t = 0; t < lanes; ++t) {
      const float dx = g.xr[t] - cx, dy = g.yr[t] - cy, dz = g.zr[t] - cz;
      const float r2 = dx * dx + dy * dy + dz * dz;
      const float h = std::max(g.spline[t], h_node);
      const float h_inv = pair_inverse_spline_length(g.spline_inv[t], h_node_inv);
      const auto f = softened_derivatives_branch_free(std::sqrt(r2), h, h_inv);
      const float qx = q[0] * dx + q[3] * dy + q[4] * dz, qy = q[3] * dx + q[1] * dy + q[5] * dz,
                  qz = q[4] * dx + q[5] * dy + q[2] * dz;
      const float dqd = dx * qx + dy * qy + dz * qz;
      const float along =
          gm * f.d1 + trace * (f.d3 * r2 * (1.0f / 6.0f) + f.d2 * (5.0f / 6.0f)) + f.d3 * dqd * (1.0f / 6.0f);
      const float across = f.d2 * (1.0f / 3.0f);
      ax[t] -= along * dx + across * qx;
      ay[t] -= along * dy + across * qy;
      az[t] -= along * dz + across * qz;
      pot[t] += gm * f.potential + f.d2 * dqd * (1.0f / 6.0f) + trace * (f.d2 * r2 * (1.0f / 6.0f) + 0.5f * f.d1);
    }
  }
  for (const std::int32_t k : list.far) {
    const float px = static_cast<float>((pos_[k].x - g.centre.x) * unit_inv),
                py = static_cast<float>((pos_[k].y - g.centre.y) * unit_inv),
                pz = static_cast<float>((pos_[k].z - g.centre.z) * unit_inv);
    const float gm = static_cast<float>(G * mass_[k] * gm_scale);
    for (int t = 0; t < lanes; ++t) {
      const float dx = g.xr[t] - px, dy = g.yr[t] - py, dz = g.zr[t] - pz;
      const float r2 = dx * dx + dy * dy + dz * dz;
      const float r_inv = 1.0f / std::sqrt(r2);
      const float s = gm * (r_inv * r_inv * r_inv);
      ax[t] -= s * dx;
      ay[t] -= s * dy;
      az[t] -= s * dz;
      pot[t] -= gm * r_inv;
    }
  }
  for (int t = 0; t < nt; ++t) {
    g.ax[t] = static_cast<double>(ax[t]) * g.accel_unit;
    g.ay[t] = static_cast<double>(ay[t]) * g.accel_unit;
    g.az[t] = static_cast<double>(az[t]) * g.accel_unit;
    g.pot[t] = static_cast<double>(pot[t]) * pot_unit;
  }
  // The near list is most of the work in a collapsed object (every particle within the
  // softening is summed directly). Its loop is branch-free (every piece of the spline is
  // computed and one selected). A target's own particle and unsoftened coincident particles
  // (no force direction) add exact zeros.
  {
    std::fill(ax, ax + kGroupSize, 0.0f);
    std::fill(ay, ay + kGroupSize, 0.0f);
    std::fill(az, az + kGroupSize, 0.0f);
    std::fill(pot, pot + kGroupSize, 0.0f);
    float owned[kGroupSize] = {};
    for (const std::int32_t k : list.near) {
      const float px = static_cast<float>((pos_[k].x - g.centre.x) * unit_inv),
                  py = static_cast<float>((pos_[k].y - g.centre.y) * unit_inv),
                  pz = static_cast<float>((pos_[k].z - g.centre.z) * unit_inv);
      const float gm = static_cast<float>(G * mass_[k] * gm_scale);
      const float h_k = spline_f_[k], h_inv_k = spline_inv_f_[k];
      const IndexKey source = index_key(index_[k]);
      for (int t = 0; t < lanes; ++t) {
        // Masks are formed by arithmetic and applied by selects: a loop combining float
        // comparisons with & or | does not vectorise. The key difference is exact (small
        // integers), zero only for the target's own particle.
        const float key_diff = std::fabs(source.hi - g.self_hi[t]) + std::fabs(source.lo - g.self_lo[t]);
        owned[t] += key_diff != 0.0f ? 0.0f : 1.0f;
        const float dx = g.xr[t] - px, dy = g.yr[t] - py, dz = g.zr[t] - pz;
        const float r2 = dx * dx + dy * dy + dz * dz;
        const float h = std::max(g.spline[t], h_k);  // pair_spline_length, from the spline lengths
        // The source's mass if it pulls (another particle, and a direction or a softening).
        // Where it does not, the kernel gets r = 1 so that the zero mass meets finite values.
        const float gm_other = key_diff != 0.0f ? gm : 0.0f;
        const float gm_pull = r2 + h != 0.0f ? gm_other : 0.0f;
        const float r = gm_pull != 0.0f ? std::sqrt(r2) : 1.0f;
        const auto f = softened_pair_branch_free(r, h, pair_inverse_spline_length(g.spline_inv[t], h_inv_k));
        const float s = gm_pull * f.force;
        ax[t] -= s * dx;
        ay[t] -= s * dy;
        az[t] -= s * dz;
        pot[t] += gm_pull * f.potential;
      }
    }
    for (int t = 0; t < nt; ++t) {
      g.ax[t] += static_cast<double>(ax[t]) * g.accel_unit;
      g.ay[t] += static_cast<double>(ay[t]) * g.accel_unit;
      g.az[t] += static_cast<double>(az[t]) * g.accel_unit;
      g.pot[t] += static_cast<double>(pot[t]) * pot_unit;
      g.own[t] = owned[t] > 0.0f ? 1 : 0;
    }
  }
}

GravityResult GravityTree::accelerate(const GravityTarget& target, const WalkConfig& config) const {
  GravityResult result;
  accelerate(std::span<const GravityTarget>(&target, 1), config, std::span<GravityResult>(&result, 1));
  return result;
}

void GravityTree::accelerate(std::span<const GravityTarget> targets, const WalkConfig& config,
                             std::span<GravityResult> results, const ForEach& for_each) const {
  if (results.size() != targets.size())
    throw std::invalid_argument("GravityTree::accelerate: targets and results differ in length");
  if (config_.periodic && !(config.split.enabled() && config.split.cutoff_radius() < 0.5 * config_.box_size))
    throw std::invalid_argument(
        "GravityTree::accelerate: a periodic tree gives the short-range force only: the walk needs a TreePM split "
        "whose cut-off is below half the box");
  for (GravityResult& r : results) r = GravityResult{};
  if (nodes_.empty() || targets.empty()) return;

  // Groups are runs of targets along a Morton curve through the root cube, so they are
  // compact in space; ties keep the callers' order, so the grouping is reproducible.
  const TreeNode& root = nodes_[0];
  const Vec3 corner = root.centre - Vec3{0.5 * root.side, 0.5 * root.side, 0.5 * root.side};
  auto morton = [&](const Vec3& x) {
    std::uint64_t key = 0;
    for (int d = 0; d < 3; ++d) {
      const double f = std::clamp((x[d] - corner[d]) / root.side, 0.0, 1.0);
      auto cell = static_cast<std::uint64_t>(f * 2097151.0);  // 21 bits per axis
      for (int b = 0; b < 21; ++b) key |= ((cell >> b) & 1u) << (3 * b + d);
    }
    return key;
  };
  std::vector<std::uint64_t> keys(targets.size());
  for (std::size_t i = 0; i < targets.size(); ++i) keys[i] = morton(targets[i].position);
  std::vector<std::size_t> order(targets.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });

  const double unit_inv = 1.0 / length_unit_;
  const double field = config.G * root.mass * unit_inv * unit_inv;
  const double accel_unit = field > 0.0 && std::isfinite(field) ? std::ldexp(1.0, std::ilogb(field)) : 1.0;
  const std::unique_ptr<const ShortRangeSplit> short_range =
      config.split.enabled() ? std::make_unique<const ShortRangeSplit>(config.split, length_unit_) : nullptr;
  // Each group is walked and evaluated alone, so groups may go in parallel: a target's answer
  // depends only on its group.
  auto walk_and_evaluate_targets = [&](std::size_t begin, std::size_t count) {
    thread_local InteractionList list;
    Group g;
    g.accel_unit = accel_unit;
    g.n = static_cast<int>(count);
    Vec3 lo = targets[order[begin]].position, hi = lo;
    g.h_max = 0.0;
    g.h_min = std::numeric_limits<double>::infinity();
    g.relative = true;
    double a_min = 0.0;
    for (int t = 0; t < g.n; ++t) {
      const GravityTarget& tg = targets[order[begin + static_cast<std::size_t>(t)]];
      g.spline[t] = static_cast<float>(spline_length(tg.softening) * unit_inv);
      g.spline_inv[t] = 1.0f / g.spline[t];
      const IndexKey key = index_key(static_cast<std::int32_t>(tg.source_index));
      g.self_hi[t] = key.hi;
      g.self_lo[t] = key.lo;
      g.ax[t] = g.ay[t] = g.az[t] = g.pot[t] = 0.0;
      g.own[t] = 0;
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], tg.position[d]);
        hi[d] = std::max(hi[d], tg.position[d]);
      }
      g.h_max = std::max(g.h_max, spline_length(tg.softening));
      g.h_min = std::min(g.h_min, spline_length(tg.softening));
      g.relative = g.relative && tg.a_old >= 0.0;
      a_min = t == 0 ? tg.a_old : std::min(a_min, tg.a_old);
    }
    g.centre = 0.5 * (lo + hi);
    g.half = 0.5 * (hi - lo);
    for (int t = 0; t < kGroupSize; ++t) {
      if (t < g.n) {
        const Vec3& x = targets[order[begin + static_cast<std::size_t>(t)]].position;
        g.xr[t] = static_cast<float>((x.x - g.centre.x) * unit_inv);
        g.yr[t] = static_cast<float>((x.y - g.centre.y) * unit_inv);
        g.zr[t] = static_cast<float>((x.z - g.centre.z) * unit_inv);
      } else {  // padding: a copy of the first target that is no particle
        g.xr[t] = g.xr[0];
        g.yr[t] = g.yr[0];
        g.zr[t] = g.zr[0];
        g.spline[t] = g.spline[0];
        g.spline_inv[t] = g.spline_inv[0];
        g.self_hi[t] = index_key(-1).hi;
        g.self_lo[t] = index_key(-1).lo;
      }
    }
    // Rounding in centre and half must not leave a target outside its own box (it would then
    // count as beyond its own particle); the margin only makes the tests stricter.
    if (g.n > 1)
      for (int d = 0; d < 3; ++d) g.half[d] += 1e-12 * (std::fabs(g.centre[d]) + g.half[d]);
    g.a_crit = config.alpha_force * a_min;
    g.short_range = short_range.get();
    walk_group(g, config, list);
    if (g.short_range)
      evaluate_group_short_range(g, config, list);
    else
      evaluate_group(g, config, list);

    for (int t = 0; t < g.n; ++t) {
      GravityResult& r = results[order[begin + static_cast<std::size_t>(t)]];
      r.acceleration = {g.ax[t], g.ay[t], g.az[t]};
      r.potential = g.pot[t];
      r.node_interactions = static_cast<std::int64_t>(list.nodes.size() + list.soft_nodes.size());
      r.particle_interactions = g.short_range ? g.kept[t]
                                              : static_cast<std::int64_t>(list.far.size() + list.near.size()) - g.own[t];
    }
  };
  // Periodic: a group's nearest images are taken from its centre, which is every target's
  // own nearest image of any source within the cut-off only while the group's half-width is
  // at most (L/2 - r_cut)/2; the rare wider group (a sparse set) is walked target by target.
  const double widest_half =
      config_.periodic ? 0.5 * (0.5 * config_.box_size - config.split.cutoff_radius()) : 0.0;
  const auto group_targets = static_cast<std::size_t>(group_size(config));
  auto walk_and_evaluate = [&](std::size_t group) {
    const std::size_t begin = group * group_targets;
    const std::size_t count = std::min<std::size_t>(group_targets, order.size() - begin);
    if (config_.periodic && count > 1) {
      Vec3 lo = targets[order[begin]].position, hi = lo;
      for (std::size_t t = 1; t < count; ++t)
        for (int d = 0; d < 3; ++d) {
          lo[d] = std::min(lo[d], targets[order[begin + t]].position[d]);
          hi[d] = std::max(hi[d], targets[order[begin + t]].position[d]);
        }
      if (std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) > 2.0 * widest_half) {
        for (std::size_t t = 0; t < count; ++t) walk_and_evaluate_targets(begin + t, 1);
        return;
      }
    }
    walk_and_evaluate_targets(begin, count);
  };
  for_each_or_serial(for_each, (order.size() + group_targets - 1) / group_targets, walk_and_evaluate);
}

}  // namespace fountain::gravity
