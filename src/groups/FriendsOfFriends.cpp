#include "groups/FriendsOfFriends.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <memory>
#include <utility>

namespace fountain::groups {

namespace {

// Lock-free union-find (each link a compare-and-swap on a root): the larger root always goes
// under the smaller, so a component's final root is its smallest index, whatever the order
// in which threads linked it.
class ConcurrentUnionFind {
 public:
  explicit ConcurrentUnionFind(std::size_t n) : parent_(std::make_unique<std::atomic<std::uint32_t>[]>(n)) {
    for (std::size_t i = 0; i < n; ++i) parent_[i].store(static_cast<std::uint32_t>(i), std::memory_order_relaxed);
  }
  std::uint32_t find(std::uint32_t i) const {
    for (;;) {
      const std::uint32_t p = parent_[i].load(std::memory_order_relaxed);
      if (p == i) return i;
      const std::uint32_t g = parent_[p].load(std::memory_order_relaxed);
      // Path halving: only ever points i further up its own chain.
      std::uint32_t expected = p;
      if (g != p) parent_[i].compare_exchange_weak(expected, g, std::memory_order_relaxed);
      i = g;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    for (;;) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a > b) std::swap(a, b);
      std::uint32_t expected = b;
      if (parent_[b].compare_exchange_strong(expected, a, std::memory_order_acq_rel)) return;
    }
  }

 private:
  std::unique_ptr<std::atomic<std::uint32_t>[]> parent_;
};

}  // namespace

std::vector<std::uint32_t> link_friends(std::span<const Vec3> points, double linking_length, double box) {
  return link_friends(PointGrid(points, linking_length, box), points, linking_length);
}

std::vector<std::uint32_t> link_friends(const PointGrid& grid, std::span<const Vec3> points, double linking_length) {
  const double l2 = linking_length * linking_length;
  ConcurrentUnionFind sets(points.size());
  const auto& cells = grid.cells();
  const auto& order = grid.order();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      const PointGrid::Cell& a = cells[c];
      grid.for_each_cell_near(a.at, 1, [&](std::size_t n) {
        // Each pair of cells once: the one of lower index does the work (and a cell alone).
        if (n < c) return;
        const PointGrid::Cell& b = cells[n];
        for (std::uint32_t p = a.first; p < a.first + a.count; ++p) {
          const std::uint32_t i = order[p];
          const std::uint32_t q0 = n == c ? p + 1 : b.first;
          for (std::uint32_t q = q0; q < b.first + b.count; ++q) {
            const std::uint32_t j = order[q];
            const Vec3 d = grid.separation(points[i], points[j]);
            if (dot(d, d) < l2) sets.unite(i, j);
          }
        }
      });
    }
  });
  std::vector<std::uint32_t> label(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) label[i] = sets.find(static_cast<std::uint32_t>(i));
  });
  return label;
}

std::vector<std::int64_t> nearest_within(const PointGrid& grid, std::span<const Vec3> points,
                                         std::span<const Vec3> queries, double radius) {
  std::vector<std::int64_t> nearest(queries.size(), -1);
  const auto& cells = grid.cells();
  const auto& order = grid.order();
  // Queries sorted by their cell, so that each cell's neighbourhood is looked up once.
  std::vector<std::pair<std::array<int, 3>, std::uint32_t>> by_cell(queries.size());
  for (std::size_t k = 0; k < queries.size(); ++k) by_cell[k] = {grid.cell_of(queries[k]), static_cast<std::uint32_t>(k)};
  std::sort(by_cell.begin(), by_cell.end());
  std::vector<std::size_t> runs;  // starts of runs of one cell
  for (std::size_t k = 0; k < by_cell.size(); ++k)
    if (k == 0 || by_cell[k].first != by_cell[k - 1].first) runs.push_back(k);
  runs.push_back(by_cell.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs.size() - 1, 16), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::size_t> near;
    for (std::size_t run = r.begin(); run != r.end(); ++run) {
      near.clear();
      grid.for_each_cell_near(by_cell[runs[run]].first, 1, [&](std::size_t c) { near.push_back(c); });
      for (std::size_t q = runs[run]; q < runs[run + 1]; ++q) {
        const std::uint32_t k = by_cell[q].second;
        double best = radius * radius;
        std::int64_t found = -1;
        for (std::size_t c : near)
          for (std::uint32_t p = cells[c].first; p < cells[c].first + cells[c].count; ++p) {
            const std::uint32_t j = order[p];
            const Vec3 d = grid.separation(queries[k], points[j]);
            const double r2 = dot(d, d);
            if (r2 < best || (r2 == best && found >= 0 && j < found)) {
              best = r2;
              found = j;
            }
          }
        nearest[k] = found;
      }
    }
  });
  return nearest;
}

}  // namespace fountain::groups
