// The walk's lists evaluated with the TreePM short-range factors: the tree's half of periodic gravity (docs/gravity.md, "Periodic TreePM").
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/VectorClones.hpp"
#include "gravity/GravityTree.hpp"
#include "gravity/GravityWalkGroup.hpp"
#include "gravity/SourceSelection.hpp"

namespace fountain::gravity {

namespace {

// Sources per step of a target's particle loops: AVX-512's float width (one register there,
// two under AVX2; the same sums in the same order on either).
constexpr int kSourceLanes = 16;
// Room past the kept sources: the padding to whole steps, or a whole register of sixteen
// floats stored at the end of the list.
constexpr int kKeptSlack = 16;

// One group's particle sources in its float frame (nearest images taken once per group), and
// one target's sources within the cut-off. A sentinel of no mass after the sources pads the
// kept list to whole steps of kSourceLanes.
struct ParticleSources {
  std::vector<float> x, y, z, gm, h, h_inv, key_hi, key_lo;
  std::vector<std::int32_t> kept;  // scratch of the portable selection
  std::vector<float> r2;
  std::vector<float> blocks;  // bound_blocks()'s boxes of the sources: six arrays
  // The kept sources' fields, contiguous so that the pair loops vectorise.
  std::vector<float> kx, ky, kz, kgm, kh, kh_inv, kkey_hi, kkey_lo;
  int count = 0, kept_count = 0;

  template <class Source>
  void gather(const std::vector<std::int32_t>& list, Source&& source) {
    count = static_cast<int>(list.size());
    const std::size_t n = list.size() + 1;
    for (auto* v : {&x, &y, &z, &gm, &h, &h_inv, &key_hi, &key_lo}) v->resize(n);
    for (auto* v : {&kx, &ky, &kz, &kgm, &kh, &kh_inv, &kkey_hi, &kkey_lo}) v->resize(list.size() + kKeptSlack);
    for (std::size_t i = 0; i < list.size(); ++i) source(list[i], i);
    gm[list.size()] = 0.0f;
    h[list.size()] = 0.0f;
    h_inv[list.size()] = FLT_MAX;
    const IndexKey none = index_key(-1);
    key_hi[list.size()] = none.hi;
    key_lo[list.size()] = none.lo;
    bound_blocks(x.data(), y.data(), z.data(), count, blocks);
  }

  // The sources with squared distance below r_cut2 from the target, in list order, padded by
  // the sentinel placed `away` from the target (so that its pair stays finite): the padded
  // count. kept_count is the unpadded one.
  // With `softened`, the fields of the softened pairs (h, 1/h, index keys) are kept too.
  int keep_within(float xt, float yt, float zt, float r_cut2, float away, bool softened) {
    const auto sentinel = static_cast<std::size_t>(count);
    x[sentinel] = xt + away;
    y[sentinel] = yt;
    z[sentinel] = zt;
    const float* in[] = {x.data(), y.data(), z.data(), gm.data(), h.data(), h_inv.data(), key_hi.data(), key_lo.data()};
    float* out[] = {kx.data(), ky.data(), kz.data(), kgm.data(), kh.data(), kh_inv.data(), kkey_hi.data(), kkey_lo.data()};
    const int fields = softened ? 8 : 4;
    const SourceFields sources{in, out, fields, count, blocks.data(), static_cast<int>(blocks.size() / 6)};
    int m = select_within(sources, xt, yt, zt, r_cut2, r2, kept);
    kept_count = m;
    for (; m % kSourceLanes != 0; ++m)
      for (int f = 0; f < fields; ++f) out[f][m] = in[f][sentinel];
    return m;
  }
};

}  // namespace

// As evaluate_group, in the same float units, with each pair's Newtonian (or softened)
// derivatives scaled by the split: the potential by g0, the force by g1, and in a node's
// quadrupole term the second and third derivatives by g2 and g3. The truncated potential is
// not harmonic, so a node's expansion keeps the trace of its second moment as well (the same
// Taylor terms as softened_node_field; with g_n = 1 they vanish). Pairs beyond the cut-off
// add nothing. Offsets are nearest images.
FOUNTAIN_WIDE_VECTOR_CLONES void GravityTree::evaluate_group_short_range(Group& g, const WalkConfig& config,
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
  // Particles: one group's list reaches every source within r_cut of any of its targets,
  // several times the ~(4/3) pi r_cut^3 n each target needs, so each target keeps its own
  // sources (in list order) before the factors are computed, sixteen at a time over sources.
  // Dropped pairs are those beyond the cut-off, which add nothing.
  thread_local ParticleSources far, near;
  // The far list's pairs need no softening or index keys.
  auto particle_source = [&](ParticleSources& into, bool softened) {
    return [&, softened, this](std::int32_t k, std::size_t i) {
      const auto [px, py, pz] = offset(pos_[k]);
      into.x[i] = px;
      into.y[i] = py;
      into.z[i] = pz;
      into.gm[i] = static_cast<float>(G * mass_[k] * gm_scale);
      if (!softened) return;
      into.h[i] = spline_f_[k];
      into.h_inv[i] = spline_inv_f_[k];
      const IndexKey key = index_key(index_[k]);
      into.key_hi[i] = key.hi;
      into.key_lo[i] = key.lo;
    };
  };
  far.gather(list.far, particle_source(far, false));
  near.gather(list.near, particle_source(near, true));
  const float r_cut2 = r_cut * r_cut;
  for (int t = 0; t < nt; ++t) {
    const float xt = g.xr[t], yt = g.yr[t], zt = g.zr[t];
    float sum_x[kSourceLanes] = {}, sum_y[kSourceLanes] = {}, sum_z[kSourceLanes] = {}, sum_pot[kSourceLanes] = {};
    const int n_far = far.keep_within(xt, yt, zt, r_cut2, 2.0f * r_cut, false);
    for (int k0 = 0; k0 < n_far; k0 += kSourceLanes)
      for (int l = 0; l < kSourceLanes; ++l) {
        const auto k = static_cast<std::size_t>(k0 + l);
        const float dx = xt - far.kx[k], dy = yt - far.ky[k], dz = zt - far.kz[k];
        const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
        const ShortRangeFactors g_n = short_range_factors(r * u_per_length, u_cut);
        const float r_inv = 1.0f / r;
        const float s = far.kgm[k] * g_n.g1 * (r_inv * r_inv * r_inv);
        sum_x[l] -= s * dx;
        sum_y[l] -= s * dy;
        sum_z[l] -= s * dz;
        sum_pot[l] -= far.kgm[k] * g_n.g0 * r_inv;
      }
    // Near particles: the spline-softened pair (softening is far below r_s) times the
    // factors; a target's own particle and unsoftened coincident ones add exact zeros, as in
    // evaluate_group.
    const IndexKey self{g.self_hi[t], g.self_lo[t]};
    const float h_t = g.spline[t], h_inv_t = g.spline_inv[t];
    float owned[kSourceLanes] = {};
    const int n_near = near.keep_within(xt, yt, zt, r_cut2, 2.0f * r_cut, true);
    for (int k0 = 0; k0 < n_near; k0 += kSourceLanes)
      for (int l = 0; l < kSourceLanes; ++l) {
        const auto k = static_cast<std::size_t>(k0 + l);
        const float key_diff = std::fabs(near.kkey_hi[k] - self.hi) + std::fabs(near.kkey_lo[k] - self.lo);
        owned[l] += key_diff != 0.0f ? 0.0f : 1.0f;
        const float dx = xt - near.kx[k], dy = yt - near.ky[k], dz = zt - near.kz[k];
        const float r2 = dx * dx + dy * dy + dz * dz;
        const float h = std::max(h_t, near.kh[k]);
        const float gm_other = key_diff != 0.0f ? near.kgm[k] : 0.0f;
        const float gm_pull = r2 + h != 0.0f ? gm_other : 0.0f;
        const float r = gm_pull != 0.0f ? std::sqrt(r2) : 1.0f;
        const ShortRangeFactors g_n = short_range_factors(r * u_per_length, u_cut);
        const auto f = softened_pair_branch_free(r, h, pair_inverse_spline_length(h_inv_t, near.kh_inv[k]));
        const float s = gm_pull * g_n.g1 * f.force;
        sum_x[l] -= s * dx;
        sum_y[l] -= s * dy;
        sum_z[l] -= s * dz;
        sum_pot[l] += gm_pull * g_n.g0 * f.potential;
      }
    for (int l = 0; l < kSourceLanes; ++l) {
      ax[t] += sum_x[l];
      ay[t] += sum_y[l];
      az[t] += sum_z[l];
      pot[t] += sum_pot[l];
    }
    float own_count = 0.0f;
    for (int l = 0; l < kSourceLanes; ++l) own_count += owned[l];
    g.own[t] = own_count > 0.0f ? 1 : 0;
    g.kept[t] = far.kept_count + near.kept_count - g.own[t];
  }
  for (int t = 0; t < nt; ++t) {
    g.ax[t] = static_cast<double>(ax[t]) * g.accel_unit;
    g.ay[t] = static_cast<double>(ay[t]) * g.accel_unit;
    g.az[t] = static_cast<double>(az[t]) * g.accel_unit;
    g.pot[t] = static_cast<double>(pot[t]) * pot_unit;
  }
}

}  // namespace fountain::gravity
