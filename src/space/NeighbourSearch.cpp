#include "space/NeighbourSearch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace fountain {

double reach_distance(const Space& space, const Vec3& p, const Cell& leaf) {
  const Vec3 d = space.separation(leaf.centre(), p);
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max(0.0, std::fabs(d[k]) - 0.5 * leaf.width[k]);
    d2 += gap * gap;
  }
  return std::max(0.0, std::sqrt(d2) - leaf.dx_max);
}

void for_each_within(const Space& space, const GasParticles& gas, const Vec3& p, double radius,
                     const std::function<void(std::size_t, const Vec3&, double)>& fn) {
  const double r2_max = radius * radius;
  for (int c : space.leaves()) {
    const Cell& cell = space.cell(c);
    if (cell.count == 0 || reach_distance(space, p, cell) >= radius) continue;
    for (std::size_t j = cell.first; j < cell.first + cell.count; ++j) {
      const Vec3 dx = space.separation(gas.x[j], p);
      const double r2 = dot(dx, dx);
      if (r2 < r2_max) fn(j, dx, std::sqrt(r2));
    }
  }
}

std::vector<std::size_t> nearest(const Space& space, const GasParticles& gas, const Vec3& p, std::size_t self,
                                 std::size_t k, double max_radius, const std::function<bool(std::size_t)>& accept) {
  const double limit = max_radius > 0.0 ? max_radius : std::numeric_limits<double>::infinity();
  // Leaves by their distance from p: scanned outward, stopping once the next leaf is
  // farther than the k-th candidate found.
  std::vector<std::pair<double, int>> order;
  order.reserve(space.leaves().size());
  for (int c : space.leaves()) {
    const Cell& cell = space.cell(c);
    if (cell.count == 0) continue;
    const double d = reach_distance(space, p, cell);
    if (d <= limit) order.emplace_back(d, c);
  }
  std::sort(order.begin(), order.end());
  // The best k so far as a max-heap on (r2, index).
  std::vector<std::pair<double, std::size_t>> best;
  best.reserve(k + 1);
  const double limit2 = limit * limit;
  for (const auto& [d, c] : order) {
    if (best.size() == k && d * d > best.front().first) break;
    const Cell& cell = space.cell(c);
    for (std::size_t j = cell.first; j < cell.first + cell.count; ++j) {
      if (j == self) continue;
      const Vec3 dx = space.separation(gas.x[j], p);
      const double r2 = dot(dx, dx);
      if (r2 > limit2) continue;
      const std::pair<double, std::size_t> cand{r2, j};
      if (best.size() == k && !(cand < best.front())) continue;
      if (!accept(j)) continue;
      best.push_back(cand);
      std::push_heap(best.begin(), best.end());
      if (best.size() > k) {
        std::pop_heap(best.begin(), best.end());
        best.pop_back();
      }
    }
  }
  std::sort(best.begin(), best.end());
  std::vector<std::size_t> out;
  out.reserve(best.size());
  for (const auto& b : best) out.push_back(b.second);
  return out;
}

}  // namespace fountain
