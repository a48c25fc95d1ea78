// The leaves' neighbour and surroundings lists against a check of every pair of leaves; top cells' octrees built apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <utility>
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

// A recut across ranks builds each top cell where its particles are: the subtree that one top
// cell's particles give alone (positions copied out in their order before the recut, as a
// rank receiving them would hold them) must be the whole recut's, cell for cell and in the
// same particle order, for gas and dark matter.
void expect_subtrees_built_apart_match(bool periodic) {
  const double box = 2.0;
  GasParticles gas;
  fill(gas, 20000, box, periodic ? 5 : 6);
  CollisionlessParticles dm;
  dm.resize(7000);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> N(0.0, 0.05 * box);
  for (std::size_t i = 0; i < dm.size(); ++i)
    for (int k = 0; k < 3; ++k) dm.x[i][k] = std::clamp(0.5 * box + N(rng), 0.0, std::nextafter(box, 0.0));
  const std::vector<Vec3> gas_x = gas.x, dm_x = dm.x;  // before the recut, in their order
  SpaceConfig config;
  config.periodic = periodic;
  config.box_size = {box, box, box};
  config.split_size = 64;
  Space space(config);
  std::vector<std::size_t> gas_order;
  space.recut(gas, dm, {}, &gas_order);
  ASSERT_EQ(gas_order.size(), gas.size());
  // Where each dark-matter particle went: positions are unique, so found by position.
  std::vector<std::pair<Vec3, std::size_t>> dm_was(dm_x.size());
  for (std::size_t i = 0; i < dm_x.size(); ++i) dm_was[i] = {dm_x[i], i};
  auto before = [](const auto& a, const auto& b) {
    return std::tie(a.first.x, a.first.y, a.first.z) < std::tie(b.first.x, b.first.y, b.first.z);
  };
  std::sort(dm_was.begin(), dm_was.end(), before);
  auto dm_index_of = [&](const Vec3& x) {
    const auto it = std::lower_bound(dm_was.begin(), dm_was.end(), std::pair{x, std::size_t{0}}, before);
    return it->second;
  };
  const auto& grid = space.top_grid();
  const int ntop = grid[0] * grid[1] * grid[2];
  ASSERT_GT(ntop, 8);
  int split_tops = 0;
  for (int t = 0; t < ntop; ++t) {
    const Cell& top = space.cell(t);
    // The top cell's particles alone, in their order before the recut.
    std::vector<std::size_t> was_gas(gas_order.begin() + static_cast<std::ptrdiff_t>(top.first),
                                     gas_order.begin() + static_cast<std::ptrdiff_t>(top.first + top.count));
    std::vector<std::size_t> was_dm;
    for (std::size_t i = top.dm_first; i < top.dm_first + top.dm_count; ++i) was_dm.push_back(dm_index_of(dm.x[i]));
    std::sort(was_gas.begin(), was_gas.end());
    std::sort(was_dm.begin(), was_dm.end());
    std::vector<Vec3> own_gas, own_dm;
    for (std::size_t i : was_gas) own_gas.push_back(gas_x[i]);
    for (std::size_t i : was_dm) own_dm.push_back(dm_x[i]);
    std::vector<std::size_t> order(own_gas.size()), scratch(own_gas.size()), dm_order(own_dm.size()),
        dm_scratch(own_dm.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    for (std::size_t k = 0; k < dm_order.size(); ++k) dm_order[k] = k;
    const std::vector<Cell> sub = space.build_subtree(top, own_gas, order, scratch, own_dm, dm_order, dm_scratch);
    // The same particles in the same places.
    for (std::size_t k = 0; k < order.size(); ++k)
      ASSERT_EQ(was_gas[order[k]], gas_order[top.first + k]) << "top cell " << t << ", gas place " << k;
    for (std::size_t k = 0; k < dm_order.size(); ++k)
      ASSERT_EQ(own_dm[dm_order[k]], dm.x[top.dm_first + k]) << "top cell " << t << ", dark matter place " << k;
    // The same cells: walked together from the top cell.
    std::vector<std::pair<int, int>> walk{{t, 0}};
    std::size_t seen = 0;
    while (!walk.empty()) {
      const auto [c, k] = walk.back();
      walk.pop_back();
      ++seen;
      const Cell& whole = space.cell(c);
      const Cell& apart = sub[static_cast<std::size_t>(k)];
      ASSERT_EQ(whole.leaf, apart.leaf) << "cell " << c;
      EXPECT_EQ(whole.first, top.first + apart.first) << "cell " << c;
      EXPECT_EQ(whole.count, apart.count) << "cell " << c;
      EXPECT_EQ(whole.dm_first, top.dm_first + apart.dm_first) << "cell " << c;
      EXPECT_EQ(whole.dm_count, apart.dm_count) << "cell " << c;
      EXPECT_EQ(whole.depth, apart.depth) << "cell " << c;
      EXPECT_EQ(whole.lo, apart.lo) << "cell " << c;
      for (std::size_t o = 0; o < 8; ++o) {
        ASSERT_EQ(whole.children[o] < 0, apart.children[o] < 0) << "cell " << c << ", octant " << o;
        if (whole.children[o] >= 0) walk.emplace_back(whole.children[o], apart.children[o]);
      }
    }
    EXPECT_EQ(seen, sub.size()) << "top cell " << t;
    if (sub.size() > 1) ++split_tops;
  }
  EXPECT_GT(split_tops, 3) << "some top cells must be split for the test to mean anything";
}

TEST(SpaceSubtrees, TopCellsBuiltFromTheirOwnParticlesMatchTheWholeRecutPeriodic) {
  expect_subtrees_built_apart_match(true);
}

TEST(SpaceSubtrees, TopCellsBuiltFromTheirOwnParticlesMatchTheWholeRecutOpen) {
  expect_subtrees_built_apart_match(false);
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
