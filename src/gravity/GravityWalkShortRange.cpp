// The walk's lists evaluated with the TreePM short-range factors: the tree's half of periodic gravity (docs/gravity.md, "Periodic TreePM").
#include <algorithm>
#include <cmath>

#include "core/VectorClones.hpp"
#include "gravity/GravityTree.hpp"
#include "gravity/GravityWalkGroup.hpp"

namespace fountain::gravity {

// As evaluate_group, in the same float units, with each pair's Newtonian (or softened)
// derivatives scaled by the split: the potential by g0, the force by g1, and in a node's
// quadrupole term the second and third derivatives by g2 and g3. The truncated potential is
// not harmonic, so a node's expansion keeps the trace of its second moment as well (the same
// Taylor terms as softened_node_field; with g_n = 1 they vanish). Pairs beyond the cut-off
// add nothing. Offsets are nearest images.
FOUNTAIN_VECTOR_CLONES void GravityTree::evaluate_group_short_range(Group& g, const WalkConfig& config,
                                                                     const InteractionList& list) const {
  const ShortRangeSplit& split = *g.short_range;
  const int nt = g.n;
  const auto [lanes, unit_inv, gm_scale, q_scale, pot_unit] = float_units(nt, length_unit_, g.accel_unit);
  const double G = config.G;
  const bool quadrupole = config.expansion == MultipoleOrder::quadrupole;
  const float u_per_length = split.u_per_length, u_cut = split.u_cut;
  const float r_cut = u_cut / u_per_length;
  auto offset = [&](const Vec3& x) {
    return std::array<float, 3>{static_cast<float>(image(x.x - g.centre.x) * unit_inv),
                                static_cast<float>(image(x.y - g.centre.y) * unit_inv),
                                static_cast<float>(image(x.z - g.centre.z) * unit_inv)};
  };
  float ax[kGroupSize] = {}, ay[kGroupSize] = {}, az[kGroupSize] = {}, pot[kGroupSize] = {};

  for (const std::int32_t k : list.nodes) {
    const TreeNode& node = nodes_[k];
    const auto [cx, cy, cz] = offset(node.com);
    const float gm = static_cast<float>(G * node.mass * gm_scale);
    float q[6] = {};
    for (int i = 0; i < 6; ++i) q[i] = quadrupole ? static_cast<float>(G * node.quadrupole[i] * q_scale) : 0.0f;
    const float trace = quadrupole ? static_cast<float>(G * node.second_moment * q_scale) : 0.0f;
    for (int t = 0; t < lanes; ++t) {
      const float dx = g.xr[t] - cx, dy = g.yr[t] - cy, dz = g.zr[t] - cz;
      const float r2 = dx * dx + dy * dy + dz * dz;
      const float r = std::sqrt(r2);
      const float inside = r < r_cut ? 1.0f : 0.0f;
      const ShortRangeFactors g_n = short_range_factors(r * u_per_length, u_cut);
      const float f0 = inside * g_n.g0, f1 = inside * g_n.g1, f2 = inside * g_n.g2, f3 = inside * g_n.g3;
      const float r_inv = 1.0f / r;
      const float r2_inv = r_inv * r_inv;
      const float r3_inv = r_inv * r2_inv;
      const float r5_inv = r3_inv * r2_inv;
      // The truncated potential's radial derivatives (1/r d/dr)^n, n = 1..3.
      const float d1 = f1 * r3_inv, d2 = -3.0f * f2 * r5_inv, d3 = 15.0f * f3 * r5_inv * r2_inv;
      const float qx = q[0] * dx + q[3] * dy + q[4] * dz, qy = q[3] * dx + q[1] * dy + q[5] * dz,
                  qz = q[4] * dx + q[5] * dy + q[2] * dz;
      const float dqd = dx * qx + dy * qy + dz * qz;
      const float along = gm * d1 + trace * (d3 * r2 * (1.0f / 6.0f) + d2 * (5.0f / 6.0f)) + d3 * dqd * (1.0f / 6.0f);
      const float across = d2 * (1.0f / 3.0f);
      ax[t] -= along * dx + across * qx;
      ay[t] -= along * dy + across * qy;
      az[t] -= along * dz + across * qz;
      pot[t] += -gm * f0 * r_inv + d2 * dqd * (1.0f / 6.0f) + trace * (d2 * r2 * (1.0f / 6.0f) + 0.5f * d1);
    }
  }
  for (const std::int32_t k : list.far) {
    const auto [px, py, pz] = offset(pos_[k]);
    const float gm = static_cast<float>(G * mass_[k] * gm_scale);
    for (int t = 0; t < lanes; ++t) {
      const float dx = g.xr[t] - px, dy = g.yr[t] - py, dz = g.zr[t] - pz;
      const float r2 = dx * dx + dy * dy + dz * dz;
      const float r = std::sqrt(r2);
      const float inside = r < r_cut ? gm : 0.0f;
      const ShortRangeFactors g_n = short_range_factors(r * u_per_length, u_cut);
      const float r_inv = 1.0f / r;
      const float s = inside * g_n.g1 * (r_inv * r_inv * r_inv);
      ax[t] -= s * dx;
      ay[t] -= s * dy;
      az[t] -= s * dz;
      pot[t] -= inside * g_n.g0 * r_inv;
    }
  }
  // Near particles: the spline-softened pair (softening is far below r_s) times the factors;
  // a target's own particle and unsoftened coincident ones add exact zeros, as in
  // evaluate_group.
  float owned[kGroupSize] = {};
  for (const std::int32_t k : list.near) {
    const auto [px, py, pz] = offset(pos_[k]);
    const float gm = static_cast<float>(G * mass_[k] * gm_scale);
    const float h_k = spline_f_[k], h_inv_k = spline_inv_f_[k];
    const IndexKey source = index_key(index_[k]);
    for (int t = 0; t < lanes; ++t) {
      const float key_diff = std::fabs(source.hi - g.self_hi[t]) + std::fabs(source.lo - g.self_lo[t]);
      owned[t] += key_diff != 0.0f ? 0.0f : 1.0f;
      const float dx = g.xr[t] - px, dy = g.yr[t] - py, dz = g.zr[t] - pz;
      const float r2 = dx * dx + dy * dy + dz * dz;
      const float h = std::max(g.spline[t], h_k);
      const float gm_other = key_diff != 0.0f ? gm : 0.0f;
      const float gm_pull = r2 + h != 0.0f ? gm_other : 0.0f;
      const float r = gm_pull != 0.0f ? std::sqrt(r2) : 1.0f;
      const float gm_in = r < r_cut ? gm_pull : 0.0f;
      const ShortRangeFactors g_n = short_range_factors(r * u_per_length, u_cut);
      const auto f = softened_pair_branch_free(r, h, pair_inverse_spline_length(g.spline_inv[t], h_inv_k));
      const float s = gm_in * g_n.g1 * f.force;
      ax[t] -= s * dx;
      ay[t] -= s * dy;
      az[t] -= s * dz;
      pot[t] += gm_in * g_n.g0 * f.potential;
    }
  }
  for (int t = 0; t < nt; ++t) {
    g.ax[t] = static_cast<double>(ax[t]) * g.accel_unit;
    g.ay[t] = static_cast<double>(ay[t]) * g.accel_unit;
    g.az[t] = static_cast<double>(az[t]) * g.accel_unit;
    g.pot[t] = static_cast<double>(pot[t]) * pot_unit;
    g.own[t] = owned[t] > 0.0f ? 1 : 0;
  }
}

}  // namespace fountain::gravity
