#include "groups/SlabsAcrossRanks.hpp"

#include <algorithm>

namespace fountain::groups {

Slabs::Slabs(std::span<const double> x, double box, Collectives* ranks) : box_(box) {
  const int count = ranks == nullptr ? 1 : ranks->size();
  if (box > 0.0) {
    lo_ = 0.0, width_ = box;
  } else {
    std::vector<double> bounds{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    for (double xi : x) bounds[0] = std::min(bounds[0], xi), bounds[1] = std::max(bounds[1], xi);
    const std::vector<double> all = gather_all(bounds, ranks);
    double lo = all[0], hi = all[1];
    for (std::size_t k = 0; k < all.size(); k += 2) lo = std::min(lo, all[k]), hi = std::max(hi, all[k + 1]);
    lo_ = std::isfinite(lo) ? lo : 0.0;
    width_ = std::isfinite(hi) && hi > lo ? hi - lo : 1.0;
  }
  std::vector<std::uint64_t> histogram(kBins, 0);
  for (double xi : x) ++histogram[static_cast<std::size_t>(bin(xi))];
  const std::vector<std::uint64_t> all = gather_all(histogram, ranks);
  std::vector<std::uint64_t> total(kBins, 0);
  for (std::size_t k = 0; k < all.size(); ++k) total[k % kBins] += all[k];
  std::uint64_t n = 0;
  for (std::uint64_t c : total) n += c;
  slab_of_bin_.resize(kBins);
  first_bin_.assign(static_cast<std::size_t>(count) + 1, kBins);
  std::uint64_t before = 0;
  for (int b = 0; b < kBins; ++b) {
    const int s = n == 0 ? 0 : static_cast<int>(std::min<std::uint64_t>(count - 1, before * static_cast<std::uint64_t>(count) / n));
    slab_of_bin_[static_cast<std::size_t>(b)] = s;
    first_bin_[static_cast<std::size_t>(s)] = std::min(first_bin_[static_cast<std::size_t>(s)], b);
    before += total[static_cast<std::size_t>(b)];
  }
  // Slabs given no bin are empty: they start where the next one does.
  for (int s = count - 1; s >= 0; --s)
    first_bin_[static_cast<std::size_t>(s)] = std::min(first_bin_[static_cast<std::size_t>(s)], first_bin_[static_cast<std::size_t>(s) + 1]);
}

}  // namespace fountain::groups
