#include "domain/DomainDecomposition.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace fountain::domain {

std::uint64_t hilbert_key(std::uint32_t i, std::uint32_t j, std::uint32_t k, int bits) {
  if (bits < 1 || bits > 21) throw std::invalid_argument("hilbert_key: bits must be in [1, 21]");
  std::uint32_t x[3] = {i, j, k};
  const std::uint32_t top = 1u << (bits - 1);
  // Skilling's AxestoTranspose: undo the excess work of the inverse, then Gray-encode.
  for (std::uint32_t q = top; q > 1; q >>= 1) {
    const std::uint32_t p = q - 1;
    for (int d = 0; d < 3; ++d) {
      if (x[d] & q) {
        x[0] ^= p;
      } else {
        const std::uint32_t t = (x[0] ^ x[d]) & p;
        x[0] ^= t;
        x[d] ^= t;
      }
    }
  }
  x[1] ^= x[0];
  x[2] ^= x[1];
  std::uint32_t t = 0;
  for (std::uint32_t q = top; q > 1; q >>= 1)
    if (x[2] & q) t ^= q - 1;
  for (auto& v : x) v ^= t;
  // The transposed form holds the key's bits spread over the three words, most significant first.
  std::uint64_t key = 0;
  for (int b = bits - 1; b >= 0; --b)
    for (int d = 0; d < 3; ++d) key = (key << 1) | ((x[d] >> b) & 1u);
  return key;
}

std::vector<int> hilbert_order(const TopGrid& grid) {
  if (grid.nx < 1 || grid.ny < 1 || grid.nz < 1) throw std::invalid_argument("hilbert_order: empty grid");
  const int longest = std::max({grid.nx, grid.ny, grid.nz});
  int bits = 1;
  while ((1 << bits) < longest) ++bits;
  std::vector<std::pair<std::uint64_t, int>> keyed;
  keyed.reserve(static_cast<std::size_t>(grid.size()));
  for (int i = 0; i < grid.nx; ++i)
    for (int j = 0; j < grid.ny; ++j)
      for (int k = 0; k < grid.nz; ++k)
        keyed.emplace_back(hilbert_key(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j),
                                       static_cast<std::uint32_t>(k), bits),
                           grid.index(i, j, k));
  std::sort(keyed.begin(), keyed.end());
  std::vector<int> order(keyed.size());
  for (std::size_t n = 0; n < keyed.size(); ++n) order[n] = keyed[n].second;
  return order;
}

std::vector<int> partition(const std::vector<int>& curve, std::span<const double> work, int ranks) {
  if (ranks < 1) throw std::invalid_argument("partition: ranks must be >= 1");
  if (curve.size() != work.size())
    throw std::invalid_argument("partition: " + std::to_string(curve.size()) + " cells on the curve but " +
                                std::to_string(work.size()) + " work figures");
  double total = 0.0;
  for (std::size_t c = 0; c < work.size(); ++c) {
    if (!(work[c] >= 0.0)) throw std::invalid_argument("partition: cell " + std::to_string(c) + " has negative or NaN work");
    total += work[c];
  }
  const bool equal = !(total > 0.0);
  if (equal) total = static_cast<double>(work.size());
  std::vector<int> owner(work.size(), 0);
  double before = 0.0;  // work of the cells earlier on the curve
  for (const int c : curve) {
    const double w = equal ? 1.0 : work[static_cast<std::size_t>(c)];
    const double mid = before + 0.5 * w;
    owner[static_cast<std::size_t>(c)] = std::min(ranks - 1, static_cast<int>(mid / total * ranks));
    before += w;
  }
  return owner;
}

double imbalance(std::span<const double> work, std::span<const int> owner, int ranks) {
  if (work.size() != owner.size()) throw std::invalid_argument("imbalance: work and owner differ in length");
  std::vector<double> per_rank(static_cast<std::size_t>(ranks), 0.0);
  for (std::size_t c = 0; c < work.size(); ++c) per_rank.at(static_cast<std::size_t>(owner[c])) += work[c];
  const double total = std::accumulate(per_rank.begin(), per_rank.end(), 0.0);
  if (!(total > 0.0)) return 0.0;
  return *std::max_element(per_rank.begin(), per_rank.end()) / (total / ranks) - 1.0;
}

}  // namespace fountain::domain
