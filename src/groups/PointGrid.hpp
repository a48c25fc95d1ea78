// A uniform grid of cubic cells over a point set, open or periodic: the group finders' neighbour lookups.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/PeriodicWrap.hpp"
#include "core/Vec3.hpp"

namespace fountain::groups {

// The points sorted by cell, and each occupied cell found by its integer coordinates through
// a hash table (most cells of a clustered set at a linking length's size are empty, so none
// is stored). Periodic: cells tile [0, box)^3 exactly (cells_per_side = floor(box / size), so
// a cell is at least `cell_size`) and separations are nearest images; open: the cells cover
// the points' bounding box.
class PointGrid {
 public:
  struct Cell {
    std::array<int, 3> at;      // integer coordinates
    std::uint32_t first = 0;    // its points: order()[first, first + count)
    std::uint32_t count = 0;
  };

  // box > 0: periodic box [0, box)^3 (points outside are folded in); box = 0: open.
  PointGrid(std::span<const Vec3> points, double cell_size, double box);

  const std::vector<Cell>& cells() const { return cells_; }
  // Point indices, cell by cell, each cell's in increasing index.
  const std::vector<std::uint32_t>& order() const { return order_; }
  // The occupied cell at integer coordinates `at` (folded into the box when periodic), or -1
  // (also for coordinates outside an open grid).
  std::int64_t find(std::array<int, 3> at) const;
  // The integer coordinates of the cell holding x (clamped into an open grid's range).
  std::array<int, 3> cell_of(const Vec3& x) const;
  // b - a, as the nearest periodic image when periodic.
  Vec3 separation(const Vec3& a, const Vec3& b) const { return nearest_image(a, b, box_); }
  double cell_size() const { return size_; }
  double box() const { return box_; }
  int cells_per_side(int k) const { return n_[static_cast<std::size_t>(k)]; }

  // Calls fn(cell index) once for each distinct occupied cell whose integer coordinates lie
  // within `reach` cells of `at` in every dimension (periodic images counted once).
  template <class Fn>
  void for_each_cell_near(std::array<int, 3> at, int reach, Fn&& fn) const {
    std::vector<std::int64_t> seen;
    for (int dx = -reach; dx <= reach; ++dx)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dz = -reach; dz <= reach; ++dz) {
          const std::int64_t c = find({at[0] + dx, at[1] + dy, at[2] + dz});
          if (c < 0) continue;
          // A periodic grid narrower than 2 reach + 1 cells meets a cell more than once.
          if (small_) {
            bool again = false;
            for (std::int64_t s : seen) again = again || s == c;
            if (again) continue;
            seen.push_back(c);
          }
          fn(static_cast<std::size_t>(c));
        }
  }

 private:
  std::uint64_t key(std::array<int, 3> at) const;
  std::array<int, 3> fold(std::array<int, 3> at) const;

  double size_ = 0.0, box_ = 0.0;
  Vec3 origin_{};
  std::array<int, 3> n_{1, 1, 1};
  bool small_ = false;  // periodic with fewer than 5 cells on a side: lookups may repeat
  std::vector<Cell> cells_;
  std::vector<std::uint32_t> order_;
  // Open addressing: (key, cell index), index -1 for an empty slot. The key is kept in the
  // slot so that a lookup reads no cell.
  std::vector<std::pair<std::uint64_t, std::int64_t>> table_;
  std::uint64_t mask_ = 0;
};

}  // namespace fountain::groups
