#include "groups/NearestNeighbours.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/Error.hpp"

namespace fountain::groups {

namespace {
constexpr std::uint32_t kLeafSize = 8;
}

NearestNeighbours::NearestNeighbours(std::span<const Vec3> points, double box) : points_(points), box_(box) {
  if (points.size() >= std::numeric_limits<std::uint32_t>::max()) throw InputError("a k-d tree holds fewer than 2^32 points");
  order_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) order_[i] = static_cast<std::uint32_t>(i);
  nodes_.reserve(2 * points.size() / kLeafSize + 2);
  if (!points.empty()) build(0, static_cast<std::uint32_t>(points.size()));
}

std::int32_t NearestNeighbours::build(std::uint32_t first, std::uint32_t count) {
  const auto at = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back({});
  Vec3 lo = points_[order_[first]], hi = lo;
  for (std::uint32_t p = first; p < first + count; ++p)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], points_[order_[p]][k]), hi[k] = std::max(hi[k], points_[order_[p]][k]);
  std::int32_t left = -1, right = -1;
  if (count > kLeafSize) {
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    const std::uint32_t half = count / 2;
    // Median split, ties by index, so the tree is the same on every run.
    std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                     [&](std::uint32_t a, std::uint32_t b) {
                       return points_[a][axis] < points_[b][axis] || (points_[a][axis] == points_[b][axis] && a < b);
                     });
    left = build(first, half);
    right = build(first + half, count - half);
  }
  Node& n = nodes_[static_cast<std::size_t>(at)];
  n.lo = lo, n.hi = hi, n.first = first, n.count = count, n.left = left, n.right = right;
  return at;
}

double NearestNeighbours::box_distance2(const Node& n, const Vec3& x) const {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    double d = std::max({0.0, n.lo[k] - x[k], x[k] - n.hi[k]});
    // Periodic: x's images one box to either side. Both x and the node's box lie in [0, L),
    // so those distances are simply x + L - hi and lo - x + L.
    if (box_ > 0.0) d = std::min({d, x[k] + box_ - n.hi[k], n.lo[k] - x[k] + box_});
    d2 += d * d;
  }
  return d2;
}

std::vector<NearestNeighbours::Neighbour> NearestNeighbours::nearest(const Vec3& x, std::size_t k) const {
  std::vector<Neighbour> found;
  SearchStack stack;
  nearest(x, k, found, stack);
  return found;
}

void NearestNeighbours::nearest(const Vec3& x, std::size_t k, std::vector<Neighbour>& heap, SearchStack& stack) const {
  // `heap` is a max-heap on (distance2, index) while searching: its front is the worst kept.
  heap.clear();
  stack.clear();
  if (nodes_.empty() || k == 0) return;
  stack.emplace_back(0, box_distance2(nodes_[0], x));
  while (!stack.empty()) {
    const auto [at, d2] = stack.back();
    stack.pop_back();
    if (heap.size() == k && d2 > heap.front().distance2) continue;
    const Node& n = nodes_[static_cast<std::size_t>(at)];
    if (n.left < 0) {
      for (std::uint32_t p = n.first; p < n.first + n.count; ++p) {
        const std::uint32_t j = order_[p];
        const Vec3 d = separation(x, points_[j]);
        const Neighbour c{dot(d, d), j};
        if (heap.size() < k) {
          heap.push_back(c);
          std::push_heap(heap.begin(), heap.end());
        } else if (c < heap.front()) {
          std::pop_heap(heap.begin(), heap.end());
          heap.back() = c;
          std::push_heap(heap.begin(), heap.end());
        }
      }
      continue;
    }
    const Node& l = nodes_[static_cast<std::size_t>(n.left)];
    const Node& r = nodes_[static_cast<std::size_t>(n.right)];
    const double dl = box_distance2(l, x), dr = box_distance2(r, x);
    // The nearer child is searched first (pushed last).
    if (dl <= dr) {
      stack.emplace_back(n.right, dr);
      stack.emplace_back(n.left, dl);
    } else {
      stack.emplace_back(n.left, dl);
      stack.emplace_back(n.right, dr);
    }
  }
  std::sort_heap(heap.begin(), heap.end());
}

}  // namespace fountain::groups
