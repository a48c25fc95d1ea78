// The leaves' neighbour and surroundings lists against a check of every pair of leaves.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "space/Space.hpp"

namespace fountain {
namespace {

// The gap between two boxes along each axis, the nearest periodic image in a box of side L
// (L = 0: open), as a length: computed here from the boxes' corners, not their centres.
double gap_between(const Cell& a, const Cell& b, double L) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    double best = 1e300;
    for (int image = -1; image <= 1; ++image) {
      if (L == 0.0 && image != 0) continue;
      const double lo = b.lo[k] + image * L, hi = lo + b.width[k];
      const double gap = std::max({0.0, lo - (a.lo[k] + a.width[k]), a.lo[k] - hi});
      best = std::min(best, gap);
    }
    d2 += best * best;
  }
  return std::sqrt(d2);
}

// Clumps of small h in a sparse background of large h, so covers differ between leaves by
// far more than a top cell.
void fill(GasParticles& gas, std::size_t n, double box, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, box);
  std::normal_distribution<double> N(0.0, 0.03 * box);
  gas.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 3 == 0) {
      gas.x[i] = {U(rng), U(rng), U(rng)};
      gas.h[i] = 0.06 * box;
    } else {
      const double c = (i % 3 == 1) ? 0.3 * box : 0.85 * box;
      for (int k = 0; k < 3; ++k) gas.x[i][k] = std::clamp(c + N(rng), 0.0, std::nextafter(box, 0.0));
      gas.h[i] = 0.01 * box;
    }
    gas.id[i] = i;
  }
}

// `fill`'s particles in a box of side `box`, cut into cells of up to 64 particles.
Space rebuilt_space(GasParticles& gas, std::size_t n, double box, bool periodic, unsigned seed) {
  CollisionlessParticles dm;
  fill(gas, n, box, seed);
  SpaceConfig config;
  config.periodic = periodic;
  config.box_size = {box, box, box};
  config.split_size = 64;
  Space space(config);
  space.rebuild(gas, dm);
  return space;
}

void expect_lists_match_every_pair(bool periodic) {
  const double box = 2.0;
  GasParticles gas;
  const Space space = rebuilt_space(gas, 30000, box, periodic, periodic ? 3 : 4);
  const auto& grid = space.top_grid();
  ASSERT_GT(grid[0] * grid[1] * grid[2], 27) << "the grid must be wider than a leaf's reach for the test to mean anything";
  const double L = periodic ? box : 0.0;
  std::size_t listed = 0;
  for (int a : space.leaves()) {
    const Cell& ca = space.cell(a);
    if (ca.count == 0) continue;
    std::vector<int> neighbours, around;
    for (int b : space.leaves()) {
      const Cell& cb = space.cell(b);
      if (b == a || cb.count == 0) continue;
      const double d = gap_between(ca, cb, L);
      // Pairs within rounding of a reach are left to either answer.
      const double tol = 1e-9 * box;
      const double reach = std::max(ca.r_cover, cb.r_cover), far = Space::surroundings_reach(ca);
      if (std::fabs(d - reach) < tol || std::fabs(d - far) < tol) continue;
      if (d < reach) neighbours.push_back(b);
      if (d < far) around.push_back(b);
    }
    std::vector<int> got = space.neighbours(a), got_around = space.surroundings(a);
    std::sort(got.begin(), got.end());
    std::sort(got_around.begin(), got_around.end());
    EXPECT_EQ(got, neighbours) << "neighbours of leaf " << a;
    EXPECT_EQ(got_around, around) << "surroundings of leaf " << a;
    listed += got.size();
  }
  EXPECT_GT(listed, space.leaves().size()) << "leaves have neighbours";
}

TEST(SpaceNeighbours, ListsHoldEveryLeafWithinReachInAPeriodicBox) { expect_lists_match_every_pair(true); }

TEST(SpaceNeighbours, ListsHoldEveryLeafWithinReachInAnOpenBox) { expect_lists_match_every_pair(false); }

// Across ranks each finds the lists of a share of the leaves and takes the rest from the
// others (Engine::share_neighbour_lists): shares found apart and set must equal the whole.
TEST(SpaceNeighbours, ListsFoundInSharesAndSetEqualThoseFoundWhole) {
  GasParticles gas;
  const Space whole = rebuilt_space(gas, 20000, 2.0, true, 5);
  const std::vector<int>& leaves = whole.leaves();
  const std::size_t n = leaves.size(), cut = n / 3;
  ASSERT_GT(cut, 10u);
  Space first = whole, rest = whole;
  first.find_neighbours({}, 0, cut);
  rest.find_neighbours({}, cut, n + 5);  // a share running past the end stops at it
  for (std::size_t l = 0; l < n; ++l) {
    const int c = leaves[l];
    // Each part found only its own share.
    EXPECT_EQ(first.neighbours(c).empty(), l >= cut || whole.neighbours(c).empty()) << "leaf slot " << l;
    EXPECT_EQ(rest.surroundings(c).empty(), l < cut || whole.surroundings(c).empty()) << "leaf slot " << l;
    if (l >= cut) first.set_lists(l, rest.neighbours(c), rest.surroundings(c));
  }
  std::size_t listed = 0;
  for (int c : leaves) {
    EXPECT_EQ(first.neighbours(c), whole.neighbours(c)) << "leaf " << c;
    EXPECT_EQ(first.surroundings(c), whole.surroundings(c)) << "leaf " << c;
    listed += whole.neighbours(c).size();
  }
  EXPECT_GT(listed, n) << "leaves have neighbours";
}

}  // namespace
}  // namespace fountain
