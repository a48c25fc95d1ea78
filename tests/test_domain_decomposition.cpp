// The domain decomposition: Hilbert ordering of the top-level grid and the cut of the curve into ranks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <vector>

#include "domain/DomainDecomposition.hpp"

namespace fountain::domain {
namespace {

struct Ijk {
  int i, j, k;
};

Ijk coordinates(const TopGrid& g, int c) { return {c / (g.ny * g.nz), (c / g.nz) % g.ny, c % g.nz}; }

int manhattan(const TopGrid& g, int a, int b) {
  const Ijk p = coordinates(g, a), q = coordinates(g, b);
  return std::abs(p.i - q.i) + std::abs(p.j - q.j) + std::abs(p.k - q.k);
}

bool is_permutation_of_grid(const std::vector<int>& order, const TopGrid& g) {
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int c = 0; c < g.size(); ++c)
    if (sorted[static_cast<std::size_t>(c)] != c) return false;
  return static_cast<int>(order.size()) == g.size();
}

// Faces between cells of different owners: the surface across which ranks exchange data.
int cut_faces(const TopGrid& g, const std::vector<int>& owner) {
  int faces = 0;
  for (int i = 0; i < g.nx; ++i)
    for (int j = 0; j < g.ny; ++j)
      for (int k = 0; k < g.nz; ++k) {
        const int o = owner[static_cast<std::size_t>(g.index(i, j, k))];
        if (i + 1 < g.nx && owner[static_cast<std::size_t>(g.index(i + 1, j, k))] != o) ++faces;
        if (j + 1 < g.ny && owner[static_cast<std::size_t>(g.index(i, j + 1, k))] != o) ++faces;
        if (k + 1 < g.nz && owner[static_cast<std::size_t>(g.index(i, j, k + 1))] != o) ++faces;
      }
  return faces;
}

TEST(HilbertCurve, KeysAreABijectionOnTheCube) {
  for (int bits : {1, 2, 3, 4}) {
    const std::uint32_t n = 1u << bits;
    std::set<std::uint64_t> keys;
    for (std::uint32_t i = 0; i < n; ++i)
      for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t k = 0; k < n; ++k) {
          const std::uint64_t key = hilbert_key(i, j, k, bits);
          ASSERT_LT(key, static_cast<std::uint64_t>(n) * n * n);
          keys.insert(key);
        }
    EXPECT_EQ(keys.size(), static_cast<std::size_t>(n) * n * n) << bits << " bits";
  }
  EXPECT_THROW(hilbert_key(0, 0, 0, 0), std::invalid_argument);
}

TEST(HilbertCurve, ConsecutiveCellsShareAFace) {
  for (int n : {2, 4, 8, 16}) {
    const TopGrid g{n, n, n};
    const std::vector<int> order = hilbert_order(g);
    ASSERT_TRUE(is_permutation_of_grid(order, g));
    for (std::size_t s = 1; s < order.size(); ++s)
      ASSERT_EQ(manhattan(g, order[s - 1], order[s]), 1) << n << "^3, step " << s;
  }
}

TEST(HilbertCurve, OtherGridsAreOrderedAndStayLocal) {
  // Not a power-of-two cube: the curve of the enclosing cube, with the outside keys skipped.
  const TopGrid g{5, 3, 7};
  const std::vector<int> order = hilbert_order(g);
  ASSERT_TRUE(is_permutation_of_grid(order, g));
  int jumps = 0;
  for (std::size_t s = 1; s < order.size(); ++s) jumps += manhattan(g, order[s - 1], order[s]) > 1 ? 1 : 0;
  EXPECT_LT(jumps, g.size() / 4);
}

TEST(Partition, EqualWorkGivesEqualContiguousRuns) {
  const TopGrid g{8, 8, 8};
  const std::vector<int> curve = hilbert_order(g);
  const std::vector<double> work(static_cast<std::size_t>(g.size()), 1.0);
  for (int ranks : {1, 2, 3, 4, 7}) {
    const std::vector<int> owner = partition(curve, work, ranks);
    std::vector<int> count(static_cast<std::size_t>(ranks), 0);
    int previous = 0;
    for (int c : curve) {
      const int o = owner[static_cast<std::size_t>(c)];
      ASSERT_GE(o, previous) << "ranks own contiguous runs of the curve";
      previous = o;
      ++count[static_cast<std::size_t>(o)];
    }
    for (int n : count) EXPECT_NEAR(n, g.size() / static_cast<double>(ranks), 1.0) << ranks << " ranks";
    EXPECT_LE(imbalance(work, owner, ranks), ranks / static_cast<double>(g.size()) + 1e-12);
  }
}

TEST(Partition, CutsFollowTheSurfaceNotTheVolume) {
  // The Hilbert curve's halves, quarters and eighths of a cube are boxes: 2 ranks cut one
  // plane of 8 x 8 faces, 4 ranks two planes, 8 ranks three (a random assignment would cut
  // 7/8 of all 1344 faces).
  const TopGrid g{8, 8, 8};
  const std::vector<int> curve = hilbert_order(g);
  const std::vector<double> work(static_cast<std::size_t>(g.size()), 1.0);
  EXPECT_EQ(cut_faces(g, partition(curve, work, 2)), 64);
  EXPECT_EQ(cut_faces(g, partition(curve, work, 4)), 128);
  EXPECT_EQ(cut_faces(g, partition(curve, work, 8)), 192);
}

TEST(Partition, MeasuredWorkMovesTheCuts) {
  const TopGrid g{4, 4, 4};
  const std::vector<int> curve = hilbert_order(g);
  std::vector<double> work(static_cast<std::size_t>(g.size()), 1.0);
  // The first quarter of the curve is three times as costly: two ranks split at its end.
  for (std::size_t s = 0; s < 16; ++s) work[static_cast<std::size_t>(curve[s])] = 3.0;
  const std::vector<int> owner = partition(curve, work, 2);
  for (std::size_t s = 0; s < curve.size(); ++s)
    EXPECT_EQ(owner[static_cast<std::size_t>(curve[s])], s < 16 ? 0 : 1) << "curve position " << s;
  EXPECT_NEAR(imbalance(work, owner, 2), 0.0, 1e-12);
  // Before the cut moved (equal halves of the curve), the imbalance is what triggers it.
  const std::vector<int> even = partition(curve, std::vector<double>(work.size(), 1.0), 2);
  const double before = imbalance(work, even, 2);
  EXPECT_NEAR(before, (16 * 3.0 + 16) / 48.0 - 1.0, 1e-12);
  EXPECT_TRUE(needs_repartition(before, 0.1));
  EXPECT_FALSE(needs_repartition(imbalance(work, owner, 2), 0.1));
}

TEST(Partition, MoreRanksThanCellsAndDegenerateWork) {
  const TopGrid g{2, 1, 1};
  const std::vector<int> curve = hilbert_order(g);
  const std::vector<int> owner = partition(curve, std::vector<double>{1.0, 1.0}, 5);
  std::set<int> used(owner.begin(), owner.end());
  EXPECT_EQ(used.size(), 2u);  // three of the five ranks own nothing
  for (int o : owner) EXPECT_LT(o, 5);
  // All-zero work (nothing measured yet) splits the cells evenly.
  const TopGrid h{4, 4, 4};
  const std::vector<int> c4 = hilbert_order(h);
  const std::vector<int> o4 = partition(c4, std::vector<double>(64, 0.0), 4);
  for (int r = 0; r < 4; ++r) EXPECT_EQ(std::count(o4.begin(), o4.end(), r), 16);
  // One cell holding all the work: its rank gets it, the others get the empty cells.
  std::vector<double> heavy(64, 0.0);
  heavy[static_cast<std::size_t>(c4[40])] = 10.0;
  const std::vector<int> oh = partition(c4, heavy, 4);
  EXPECT_EQ(oh[static_cast<std::size_t>(c4[40])], 2);
  EXPECT_NEAR(imbalance(heavy, oh, 4), 3.0, 1e-12);
}

TEST(Partition, RejectsBadInput) {
  const std::vector<int> curve{0, 1};
  EXPECT_THROW(partition(curve, std::vector<double>{1.0}, 2), std::invalid_argument);
  EXPECT_THROW(partition(curve, std::vector<double>{1.0, -1.0}, 2), std::invalid_argument);
  EXPECT_THROW(partition(curve, std::vector<double>{1.0, 1.0}, 0), std::invalid_argument);
}

}  // namespace
}  // namespace fountain::domain
