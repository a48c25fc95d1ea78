// The walk's private working set: a group of targets, its interaction list, and the short-range factors of TreePM.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "gravity/GravityTree.hpp"

namespace fountain::gravity {

// Targets per group. The walk's decisions are shared by the group and the evaluation loops
// run over its targets (vectorised), so larger groups cost fewer decisions per target but
// longer lists, as each node is judged from the group's box rather than from one point.
constexpr int kGroupSize = GravityTree::kGroupSize;

struct ShortRangeTable;

struct GravityTree::Group {
  int n = 0;
  double ax[kGroupSize], ay[kGroupSize], az[kGroupSize], pot[kGroupSize];
  // For the float loops, padded to 8 or 16 lanes: positions relative to `centre` and spline
  // lengths (both in units of the tree's length_unit_) and their inverses, and the targets'
  // source indices (-1 in the padding) as two exact floats (a loop mixing int and float lanes
  // does not vectorise).
  float xr[kGroupSize], yr[kGroupSize], zr[kGroupSize], spline[kGroupSize], spline_inv[kGroupSize];
  float self_hi[kGroupSize], self_lo[kGroupSize];
  int own[kGroupSize];    // 1 if the target's own particle is on the near list (not an interaction)
  Vec3 centre, half;      // the box around the targets' positions
  // The float loops' unit of acceleration: a power of two near the whole tree's G M / unit^2,
  // so that accelerations, and the quadrupole products on the way, stay far from float's
  // subnormals and overflow whatever the unit system.
  double accel_unit = 1.0;
  double h_max = 0.0;     // the largest target spline length
  double h_min = 0.0;     // the smallest
  double a_crit = 0.0;    // alpha_force times the smallest |a_old|
  bool relative = true;   // false if any target lacks |a_old|: Barnes-Hut for the group
  const ShortRangeTable* short_range = nullptr;  // TreePM: the split's factors; null: the whole force
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
// accelerations in the group's accel_unit. Lanes: the group padded to 8 or 16.
struct FloatUnits {
  int lanes;
  double unit_inv, gm_scale, q_scale, pot_unit;
};
inline FloatUnits float_units(int targets, double length_unit, double accel_unit) {
  FloatUnits f;
  f.lanes = targets <= 8 ? 8 : kGroupSize;
  f.unit_inv = 1.0 / length_unit;
  f.gm_scale = f.unit_inv * f.unit_inv / accel_unit;
  f.q_scale = f.gm_scale * f.unit_inv * f.unit_inv;
  f.pot_unit = length_unit * accel_unit;
  return f;
}

// The TreePM short-range factors g_n(u), u = r / (2 r_s), of GravitySplit (force_factor is
// g_1, potential_factor g_0, then the second and third derivatives' factors), tabulated in
// float on [0, u_cut] for the walk's float loops (linear interpolation, error ~1e-7, below
// float's own), and 0 beyond the cut-off, as the short range is there.
struct ShortRangeTable {
  static constexpr int kBins = 2048;
  float u_per_length = 0.0f;  // 1 / (2 r_s), in the tree's float length unit
  float bins_per_u = 0.0f;
  float u_cut = 0.0f;
  std::array<float, kBins + 2> g0{}, g1{}, g2{}, g3{};

  ShortRangeTable(const GravitySplit& split, double length_unit) {
    const double u_cut_d = split.cutoff_radius() / (2.0 * split.r_s);
    u_per_length = static_cast<float>(length_unit / (2.0 * split.r_s));
    bins_per_u = static_cast<float>(kBins / u_cut_d);
    u_cut = static_cast<float>(u_cut_d);
    for (int i = 0; i <= kBins + 1; ++i) {
      const double r = 2.0 * split.r_s * u_cut_d * i / kBins;
      g0[static_cast<std::size_t>(i)] = static_cast<float>(split.potential_factor(r));
      g1[static_cast<std::size_t>(i)] = static_cast<float>(split.force_factor(r));
      g2[static_cast<std::size_t>(i)] = static_cast<float>(split.second_derivative_factor(r));
      g3[static_cast<std::size_t>(i)] = static_cast<float>(split.third_derivative_factor(r));
    }
  }
};

}  // namespace fountain::gravity
