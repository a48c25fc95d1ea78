#include "gravity/GravityTree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace fountain::gravity {

namespace {

// Below this depth a node's side is still far above a double's resolution of any sane
// coordinate; deeper nodes are kept as (over-full) leaves, so coincident particles end the
// recursion instead of looping forever.
constexpr int kMaxDepth = 48;

int octant(const Vec3& x, const Vec3& centre) {
  return (x.x >= centre.x ? 1 : 0) | (x.y >= centre.y ? 2 : 0) | (x.z >= centre.z ? 4 : 0);
}

void check_inputs(std::span<const Vec3> positions, std::span<const double> masses,
                  std::span<const double> softenings, const TreeConfig& config) {
  if (masses.size() != positions.size() || softenings.size() != positions.size())
    throw std::invalid_argument("GravityTree: positions, masses and softenings differ in length");
  if (positions.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument("GravityTree: too many sources for 32-bit node ranges");
  if (config.max_leaf_size < 1) throw std::invalid_argument("GravityTree: max_leaf_size must be >= 1");
  if (config.periodic)
    throw std::invalid_argument("GravityTree: periodic boundaries need TreePM, not implemented yet");
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3& x = positions[i];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z) || !std::isfinite(masses[i]) ||
        masses[i] < 0.0 || !std::isfinite(softenings[i]) || softenings[i] < 0.0)
      throw std::invalid_argument("GravityTree: source " + std::to_string(i) +
                                  " has a non-finite position or a negative/non-finite mass or softening");
  }
}

}  // namespace

GravityTree::GravityTree(std::span<const Vec3> positions, std::span<const double> masses,
                         std::span<const double> softenings, const TreeConfig& config)
    : config_(config) {
  check_inputs(positions, masses, softenings, config);
  const auto n = static_cast<std::int32_t>(positions.size());
  index_.resize(n);
  for (std::int32_t i = 0; i < n; ++i) index_[i] = i;
  if (n == 0) return;

  Vec3 lo = positions[0], hi = positions[0];
  for (const Vec3& x : positions)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], x[d]);
      hi[d] = std::max(hi[d], x[d]);
    }
  double side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  // A hair of margin keeps particles on the upper faces inside the cube after rounding.
  side = side > 0.0 ? side * (1.0 + 1e-9) : 1.0;
  const Vec3 centre = 0.5 * (lo + hi);

  std::vector<std::int32_t> scratch(n);
  nodes_.reserve(2 * static_cast<std::size_t>(n) / config_.max_leaf_size + 16);
  build(0, n, centre, side, 0, scratch, positions, masses, softenings);
  for (TreeNode& node : nodes_)
    if (node.next == static_cast<std::int32_t>(nodes_.size())) node.next = -1;

  pos_.resize(n);
  mass_.resize(n);
  spline_.resize(n);
  spline_f_.resize(n);
  spline_inv_f_.resize(n);
  for (std::int32_t k = 0; k < n; ++k) {
    pos_[k] = positions[index_[k]];
    mass_[k] = masses[index_[k]];
    spline_[k] = spline_length(softenings[index_[k]]);
    spline_f_[k] = static_cast<float>(spline_[k]);
    spline_inv_f_[k] = 1.0f / spline_f_[k];
  }
}

// Sequential depth-first build: nodes come out in preorder, so a node's first child is the
// next node and its subtree ends where `next` points. Partitions are stable counting sorts,
// so the tree depends only on the input order.
void GravityTree::build(std::int32_t first, std::int32_t count, const Vec3& centre, double side, int depth,
                        std::vector<std::int32_t>& scratch, std::span<const Vec3> positions,
                        std::span<const double> masses, std::span<const double> softenings) {
  const auto self = static_cast<std::int32_t>(nodes_.size());
  TreeNode node;
  node.centre = centre;
  node.side = side;
  node.first = first;
  node.count = count;

  Vec3 weighted;
  for (std::int32_t k = first; k < first + count; ++k) {
    const std::int32_t i = index_[k];
    node.mass += masses[i];
    weighted += masses[i] * positions[i];
    node.max_softening = std::max(node.max_softening, softenings[i]);
  }
  // A massless node still needs a finite position for the distance tests.
  node.com = node.mass > 0.0 ? weighted * (1.0 / node.mass) : centre;
  auto& q = node.quadrupole;
  for (std::int32_t k = first; k < first + count; ++k) {
    const std::int32_t i = index_[k];
    const Vec3 s = positions[i] - node.com;
    const double m = masses[i], s2 = dot(s, s);
    q[0] += m * (3.0 * s.x * s.x - s2);
    q[1] += m * (3.0 * s.y * s.y - s2);
    q[2] += m * (3.0 * s.z * s.z - s2);
    q[3] += m * 3.0 * s.x * s.y;
    q[4] += m * 3.0 * s.x * s.z;
    q[5] += m * 3.0 * s.y * s.z;
  }
  nodes_.push_back(node);

  if (count > config_.max_leaf_size && depth < kMaxDepth) {
    std::array<std::int32_t, 9> start{};
    for (std::int32_t k = first; k < first + count; ++k) ++start[octant(positions[index_[k]], centre) + 1];
    for (int o = 0; o < 8; ++o) start[o + 1] += start[o];
    std::array<std::int32_t, 8> fill{};
    for (std::int32_t k = first; k < first + count; ++k) {
      const int o = octant(positions[index_[k]], centre);
      scratch[first + start[o] + fill[o]++] = index_[k];
    }
    std::copy(scratch.begin() + first, scratch.begin() + first + count, index_.begin() + first);

    nodes_[self].first_child = self + 1;
    const double child_side = 0.5 * side;
    for (int o = 0; o < 8; ++o) {
      const std::int32_t child_count = start[o + 1] - start[o];
      if (child_count == 0) continue;
      const Vec3 child_centre{centre.x + ((o & 1) ? 0.25 : -0.25) * side,
                              centre.y + ((o & 2) ? 0.25 : -0.25) * side,
                              centre.z + ((o & 4) ? 0.25 : -0.25) * side};
      build(first + start[o], child_count, child_centre, child_side, depth + 1, scratch, positions, masses,
            softenings);
    }
  }
  nodes_[self].next = static_cast<std::int32_t>(nodes_.size());
}

}  // namespace fountain::gravity
