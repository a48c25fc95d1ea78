// Friends-of-friends linking (Davis et al. 1985): the connected components of the pairs closer than a linking length.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "core/Vec3.hpp"
#include "groups/PointGrid.hpp"

namespace fountain::groups {

// The component of each point in the graph whose edges join points closer than
// `linking_length` (nearest images in a periodic box of side `box` > 0): label[i] is the
// smallest index in i's component. Threaded over grid cells with a lock-free union-find
// that always hangs the larger root under the smaller, so the labels are the same for any
// thread count.
std::vector<std::uint32_t> link_friends(std::span<const Vec3> points, double linking_length, double box);
// The same on a grid of those points whose cells are at least linking_length wide.
std::vector<std::uint32_t> link_friends(const PointGrid& grid, std::span<const Vec3> points, double linking_length);

// For each query, the index of the nearest of `grid`'s points (`points` being the set it was
// built on) closer than `radius`, ties to the smaller index; -1 where there is none.
// The grid's cells must be at least `radius` wide.
std::vector<std::int64_t> nearest_within(const PointGrid& grid, std::span<const Vec3> points,
                                         std::span<const Vec3> queries, double radius);

}  // namespace fountain::groups
