// The walk's private working set: a group of targets, its interaction list, and the short-range factors of TreePM.
#pragma once
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "gravity/GravityTree.hpp"

namespace fountain::gravity {

// Targets per group. The walk's decisions are shared by the group and the evaluation loops
// run over its targets (vectorised), so larger groups cost fewer decisions per target but
// longer lists, as each node is judged from the group's box rather than from one point.
constexpr int kGroupSize = GravityTree::kGroupSize;

struct ShortRangeSplit;

struct GravityTree::Group {
  int n = 0;
  double ax[kGroupSize], ay[kGroupSize], az[kGroupSize], pot[kGroupSize];
  // For the float loops, padded to 8, 16 or 32 lanes: positions relative to `centre` and spline
  // lengths (both in units of the tree's length_unit_) and their inverses, and the targets'
  // source indices (-1 in the padding) as two exact floats (a loop mixing int and float lanes
  // does not vectorise).
  float xr[kGroupSize], yr[kGroupSize], zr[kGroupSize], spline[kGroupSize], spline_inv[kGroupSize];
  float self_hi[kGroupSize], self_lo[kGroupSize];
  int own[kGroupSize];    // 1 if the target's own particle is on the near list (not an interaction)
  int kept[kGroupSize];   // TreePM: the particle pairs within the cut-off, per target
  Vec3 centre, half;      // the box around the targets' positions
  // The float loops' unit of acceleration: a power of two near the whole tree's G M / unit^2,
  // so that accelerations, and the quadrupole products on the way, stay far from float's
  // subnormals and overflow whatever the unit system.
  double accel_unit = 1.0;
  double h_max = 0.0;     // the largest target spline length
  double h_min = 0.0;     // the smallest
  double a_crit = 0.0;    // alpha_force times the smallest |a_old|
  bool relative = true;   // false if any target lacks |a_old|: Barnes-Hut for the group
  const ShortRangeSplit* short_range = nullptr;  // TreePM: the split; null: the whole force
};

// What one walk accepted. Nodes and particles are split by whether the Newtonian force holds
// for the whole group (beyond every pair's spline length): `nodes` and `far` are evaluated
// with it, `soft_nodes` and `near` with the spline (per target, without branches).
struct GravityTree::InteractionList {
  std::vector<std::int32_t> nodes, soft_nodes, far, near;
  void clear() {
    nodes.clear();
    soft_nodes.clear();
    far.clear();
    near.clear();
  }
};

// A 32-bit index as two floats, each exact (12 and 20 bits): equal keys, equal indices.
struct IndexKey {
  float hi, lo;
};
inline IndexKey index_key(std::int32_t i) { return {static_cast<float>(i >> 12), static_cast<float>(i & 4095)}; }

// The float loops' scalings for one group (evaluate_group, evaluate_group_short_range):
// lengths in the tree's length unit, a source's G m in length^2 x acceleration (a
// quadrupole's G Q in length^4 x acceleration), potentials in length x acceleration, with
// accelerations in the group's accel_unit. Lanes: the group padded to 8, 16, 32 or 64.
struct FloatUnits {
  int lanes;
  double unit_inv, gm_scale, q_scale, pot_unit;
};
inline FloatUnits float_units(int targets, double length_unit, double accel_unit) {
  FloatUnits f;
  f.lanes = targets <= 8 ? 8 : targets <= 16 ? 16 : targets <= 32 ? 32 : kGroupSize;
  f.unit_inv = 1.0 / length_unit;
  f.gm_scale = f.unit_inv * f.unit_inv / accel_unit;
  f.q_scale = f.gm_scale * f.unit_inv * f.unit_inv;
  f.pot_unit = length_unit * accel_unit;
  return f;
}

// exp(x) for -88 < x <= 0 in float, branch-free so that loops over lanes vectorise: x / ln 2
// split into a whole n and a rest r in (-1/2, 1/2], 2^r by its Taylor series to r^7 (error
// 5e-9), 2^n put together from its exponent bits. Relative error ~1e-7, as float's own.
inline float exp_negative(float x) {
  const float z = x * 1.44269504f;
  const int n = static_cast<int>(z - 0.5f);  // truncation of a value <= -1/2 rounds it up
  const float y = (z - static_cast<float>(n)) * 0.693147181f;
  const float p =
      1.0f + y * (1.0f + y * (0.5f + y * (1.0f / 6.0f + y * (1.0f / 24.0f + y * (1.0f / 120.0f +
                                                                                      y * (1.0f / 720.0f + y * (1.0f / 5040.0f)))))));
  return p * std::bit_cast<float>((n + 127) << 23);
}

// The TreePM short-range factors g_n(u), u = r / (2 r_s), of GravitySplit in float (force_factor
// is g_1, potential_factor g_0, then the second and third derivatives' factors). Each is
// exp(-u^2) times a smooth function, so one exponential serves all four: erfc(u) exp(u^2) is a
// polynomial of degree 8 in t = 1/(1 + u/2) - 3/4 (a least-squares fit weighted for relative
// error, 1.5e-9 on 0 <= u <= 2.5; the cut-off is at 2.25), and the rest are the Gaussian's
// terms. No table and no branch, so the walk's loops over targets vectorise. u is clamped at
// the cut-off, beyond which the callers drop the pair.
struct ShortRangeFactors {
  float g0, g1, g2, g3;
};
inline ShortRangeFactors short_range_factors(float u, float u_cut) {
  u = std::min(u, u_cut);
  const float x = 1.0f / (1.0f + 0.5f * u) - 0.75f;
  const float scaled_erfc =
      0.539284408f +
      x * (1.45540725f +
           x * (1.427223f +
                x * (0.550929222f +
                     x * (-0.208038418f +
                          x * (-0.163863986f + x * (0.104674594f + x * (0.03445961f + x * -0.0598504988f)))))));
  const float u2 = u * u;
  const float gauss = exp_negative(-u2);
  const float erfc = gauss * scaled_erfc;
  const float c = 0.564189584f * u * gauss;  // u exp(-u^2) / sqrt(pi)
  return {erfc, erfc + 2.0f * c, erfc + c * (2.0f + (4.0f / 3.0f) * u2),
          erfc + c * (2.0f + u2 * (4.0f / 3.0f + (8.0f / 15.0f) * u2))};
}

// The walk's view of a TreePM split: u per float length unit and the cut-off in u.
struct ShortRangeSplit {
  float u_per_length = 0.0f;  // 1 / (2 r_s), in the tree's float length unit
  float u_cut = 0.0f;
  ShortRangeSplit(const GravitySplit& split, double length_unit)
      : u_per_length(static_cast<float>(length_unit / (2.0 * split.r_s))),
        u_cut(static_cast<float>(split.cutoff_radius() / (2.0 * split.r_s))) {}
};

// The gap between the group's box and a point or a cube, per axis.
inline double gap(double offset, double reach) { return std::max(std::fabs(offset) - reach, 0.0); }

// The widest a node within the softening may be against its distance (side / distance from
// the box to its centre of mass). The relative criterion alone admits light nodes seen under
// any angle (error ~ alpha |a_old| each); outside the softening such nodes are few, inside
// it, in a collapsed disc's halo, they were the largest errors (1.4e-2 on the softened-disc
// test, 4.8e-3 with this cap, as without softened nodes at all; docs/gravity.md).
constexpr double kSoftenedNodeAngle = 0.5;

inline GravityTree::WalkRules GravityTree::walk_rules(const WalkConfig& config, const TreeNode& root) {
  WalkRules r;
  r.theta2 = config.theta * config.theta;
  r.split = config.split.enabled();
  r.cutoff = config.split.cutoff_radius();
  r.soft_allowed = config.softened_nodes && config.expansion == MultipoleOrder::quadrupole && !r.split;
  // Above the rounding of any gap computed inside the root cube.
  r.slack = 1e-12 * (root.side + std::fabs(root.centre.x) + std::fabs(root.centre.y) + std::fabs(root.centre.z));
  return r;
}

// Every test is the one-target test applied to the nearest point of the group's box, so a
// group of one decides exactly as a single target would, and each target of a larger group
// meets every criterion at least as strictly as it would alone.
inline GravityTree::Visit GravityTree::decide(const TreeNode& node, const Group& g, const WalkConfig& config,
                                       const WalkRules& rules, NodeOffsets& o) const {
  const double half = 0.5 * node.side;
  o.ox = image(node.centre.x - g.centre.x);
  o.oy = image(node.centre.y - g.centre.y);
  o.oz = image(node.centre.z - g.centre.z);
  const double gx = gap(o.ox, half + g.half.x), gy = gap(o.oy, half + g.half.y), gz = gap(o.oz, half + g.half.z);
  o.d2box = gx * gx + gy * gy + gz * gz;
  // GADGET-2's safety check: a target within the cube grown by 10% per side opens it.
  const double grown = 0.6 * node.side;
  const bool inside_enlarged = std::fabs(o.ox) < grown + g.half.x && std::fabs(o.oy) < grown + g.half.y &&
                               std::fabs(o.oz) < grown + g.half.z;
  o.h = std::max(g.h_max, spline_length(node.max_softening));
  if (rules.split && o.d2box > rules.cutoff * rules.cutoff) return Visit::skip;  // the mesh has it
  // A node beyond every pair's spline length from the whole box takes the Newtonian
  // expansion; one within it (softened_nodes) the softened one, judged by the same criterion
  // (the softened field's derivatives are no larger than the Newtonian ones at the same
  // distance, so the criterion bounds its neglected terms at least as well), but only when
  // it is also seen under a small angle (kSoftenedNodeAngle) and every target pairs with all
  // its particles at one spline length per target: the node's softenings are all alike, or
  // no larger than any target's.
  const bool beyond = o.d2box >= o.h * o.h;
  if (!inside_enlarged && (beyond || rules.soft_allowed)) {
    const double cx = gap(image(node.com.x - g.centre.x), g.half.x), cy = gap(image(node.com.y - g.centre.y), g.half.y),
                 cz = gap(image(node.com.z - g.centre.z), g.half.z);
    const double r2 = cx * cx + cy * cy + cz * cz;
    const double l2 = node.side * node.side;
    bool accept = false;
    if (!g.relative) {
      accept = l2 <= rules.theta2 * r2;
    } else if (config.criterion == OpeningCriterion::gadget2_monopole) {
      accept = config.G * node.mass * l2 <= g.a_crit * r2 * r2;  // G M l^2 / r^4 <= alpha |a_old|
    } else {
      accept = config.G * node.mass * l2 * node.side <= g.a_crit * r2 * r2 * std::sqrt(r2);  // G M l^3 / r^5
    }
    if (accept && !beyond)
      accept = l2 <= kSoftenedNodeAngle * kSoftenedNodeAngle * r2 &&
               (node.min_softening == node.max_softening || g.h_min >= spline_length(node.max_softening));
    if (accept) return beyond ? Visit::accept : Visit::accept_softened;
  }
  // Another rank's node whose inside that rank did not send (TreeAcrossRanks): no walk it
  // sent the node for opens it, so reaching here is a logic error the caller reports.
  if (node.first_child == TreeNode::kPruned) return Visit::pruned;
  // TreePM: a node of at most kDirectNodeSize particles gives its particles at once (the short
  // range at high redshift opens nearly every node within the cut-off down to its leaves).
  if (node.first_child >= 0 && !(rules.split && node.count <= kDirectNodeSize)) return Visit::open;
  return Visit::list;
}

}  // namespace fountain::gravity
