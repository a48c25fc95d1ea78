// The bounding box of points spread over MPI ranks, from each rank's own box.
#pragma once
#include <algorithm>
#include <array>
#include <span>

#include "core/Vec3.hpp"
#include "domain/RankExchange.hpp"

namespace fountain::domain {

// Widens [lo, hi] (this rank's box; empty as lo = +big, hi = -big) to every rank's: a minimum
// and maximum, exact in any order.
inline void widen_to_every_rank(const RankExchange& ranks, Vec3& lo, Vec3& hi, const char* what) {
  const std::array<double, 6> mine{lo.x, lo.y, lo.z, -hi.x, -hi.y, -hi.z};
  for (const auto& b : ranks.allgather_values(std::span<const double>(mine), what))
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], b[static_cast<std::size_t>(k)]);
      hi[k] = std::max(hi[k], -b[static_cast<std::size_t>(k + 3)]);
    }
}

}  // namespace fountain::domain
