#include "groups/PointGrid.hpp"

#include <fmt/format.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"

namespace fountain::groups {

namespace {
constexpr int kMaxCellsPerSide = 1 << 20;  // keys pack three 21-bit coordinates

std::uint64_t mix(std::uint64_t k) {  // splitmix64's finaliser: spreads neighbouring keys
  k ^= k >> 30;
  k *= 0xbf58476d1ce4e5b9ULL;
  k ^= k >> 27;
  k *= 0x94d049bb133111ebULL;
  return k ^ (k >> 31);
}
}  // namespace

PointGrid::PointGrid(std::span<const Vec3> points, double cell_size, double box) : size_(cell_size), box_(box) {
  if (!(cell_size > 0.0)) throw InputError("a point grid needs a positive cell size");
  if (points.size() >= std::numeric_limits<std::uint32_t>::max())
    throw InputError("a point grid holds fewer than 2^32 points");
  Vec3 lo{}, hi{};
  if (box > 0.0) {
    const int n = static_cast<int>(std::clamp(std::floor(box / cell_size), 1.0, static_cast<double>(kMaxCellsPerSide)));
    n_ = {n, n, n};
    size_ = box / n;
    small_ = n < 5;
  } else if (!points.empty()) {
    lo = hi = points[0];
    for (const Vec3& p : points)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    for (int k = 0; k < 3; ++k)
      n_[static_cast<std::size_t>(k)] = static_cast<int>(
          std::clamp(std::floor((hi[k] - lo[k]) / cell_size) + 1.0, 1.0, static_cast<double>(kMaxCellsPerSide)));
    origin_ = lo;
  }
  // Each point's cell key, then the points sorted by (key, index): deterministic.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y) || !std::isfinite(points[i].z))
      throw InputError(fmt::format("point {} of a group search is not finite", i));
    keyed[i] = {key(cell_of(points[i])), static_cast<std::uint32_t>(i)};
  }
  tbb::parallel_sort(keyed.begin(), keyed.end());
  order_.resize(points.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    order_[i] = keyed[i].second;
    if (i == 0 || keyed[i].first != keyed[i - 1].first) {
      Cell c;
      c.at = cell_of(points[keyed[i].second]);
      c.first = static_cast<std::uint32_t>(i);
      cells_.push_back(c);
    }
    ++cells_.back().count;
  }
  const std::size_t capacity = std::bit_ceil(std::max<std::size_t>(16, 2 * cells_.size()));
  mask_ = capacity - 1;
  table_.assign(capacity, {0, -1});
  for (std::size_t c = 0; c < cells_.size(); ++c) {
    const std::uint64_t k = key(cells_[c].at);
    std::uint64_t slot = mix(k) & mask_;
    while (table_[slot].second >= 0) slot = (slot + 1) & mask_;
    table_[slot] = {k, static_cast<std::int64_t>(c)};
  }
}

std::uint64_t PointGrid::key(std::array<int, 3> at) const {
  return (static_cast<std::uint64_t>(at[0]) << 42) | (static_cast<std::uint64_t>(at[1]) << 21) |
         static_cast<std::uint64_t>(at[2]);
}

std::array<int, 3> PointGrid::fold(std::array<int, 3> at) const {
  for (int k = 0; k < 3; ++k) {
    const int n = n_[static_cast<std::size_t>(k)];
    at[static_cast<std::size_t>(k)] = ((at[static_cast<std::size_t>(k)] % n) + n) % n;
  }
  return at;
}

std::array<int, 3> PointGrid::cell_of(const Vec3& x) const {
  std::array<int, 3> at{};
  for (int k = 0; k < 3; ++k) {
    const double u = box_ > 0.0 ? wrap_into_box(x[k], box_) : x[k] - origin_[k];
    at[static_cast<std::size_t>(k)] =
        std::clamp(static_cast<int>(std::floor(u / size_)), 0, n_[static_cast<std::size_t>(k)] - 1);
  }
  return at;
}

std::int64_t PointGrid::find(std::array<int, 3> at) const {
  if (box_ > 0.0) {
    at = fold(at);
  } else {
    for (int k = 0; k < 3; ++k)
      if (at[static_cast<std::size_t>(k)] < 0 || at[static_cast<std::size_t>(k)] >= n_[static_cast<std::size_t>(k)])
        return -1;
  }
  const std::uint64_t wanted = key(at);
  for (std::uint64_t slot = mix(wanted) & mask_;; slot = (slot + 1) & mask_) {
    const auto& [k, c] = table_[slot];
    if (c < 0) return -1;
    if (k == wanted) return c;
  }
}

}  // namespace fountain::groups
