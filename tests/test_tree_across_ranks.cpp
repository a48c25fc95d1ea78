// The gravity tree assembled across ranks (ranks run as threads) against one rank's tree: the same forces, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <stdexcept>
#include <vector>

#include "gravity/GravityTree.hpp"
#include "gravity/TreeAcrossRanks.hpp"
#include "ThreadRanks.hpp"

using namespace fountain;
using namespace fountain::gravity;
using fountain::test_ranks::ThreadRanks;

namespace {


// A clustered set: two Plummer-like clumps and a uniform background, with two softenings
// (as gas and dark matter) and masses that vary.
struct Sources {
  std::vector<Vec3> x;
  std::vector<double> m, eps;
};
Sources clustered(std::size_t n, double box, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Sources s;
  const Vec3 centres[2] = {{0.3 * box, 0.4 * box, 0.5 * box}, {0.7 * box, 0.6 * box, 0.45 * box}};
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 x;
    if (i % 3 == 2) {
      x = {u(rng) * box, u(rng) * box, u(rng) * box};
    } else {
      const double r = 0.05 * box / std::sqrt(std::pow(u(rng) * 0.95 + 0.01, -2.0 / 3.0) - 1.0 + 1e-3);
      const double c = 2.0 * u(rng) - 1.0, phi = 6.283185307179586 * u(rng);
      const double sn = std::sqrt(1.0 - c * c);
      x = centres[i % 3] + Vec3{std::min(r, 0.2 * box) * sn * std::cos(phi), std::min(r, 0.2 * box) * sn * std::sin(phi),
                                std::min(r, 0.2 * box) * c};
      for (int d = 0; d < 3; ++d) x[d] = std::clamp(x[d], 0.0, box * (1.0 - 1e-12));
    }
    s.x.push_back(x);
    s.m.push_back((i % 2 ? 1.0 : 5.0) * (0.5 + u(rng)) / static_cast<double>(n));
    s.eps.push_back(i % 2 ? 0.002 * box : 0.004 * box);
  }
  return s;
}

struct Case {
  TreeConfig tree;
  WalkConfig walk;
};

// Each rank's sources by a rule; its batches are its sources in each cell of a coarse grid,
// every other one active, the targets' |a_old| from a first walk of the whole tree (or none
// for a Barnes-Hut start). Each rank's walks of its batches on its assembled tree must equal
// the whole tree's walks of the same batches.
// With `moved`, both trees are built at s.x and then refitted to `moved` (as a run's steps
// between rebuilds refit them), and the walks are made there.
void expect_same_forces(const Sources& built, const Case& c, int ranks, const std::function<int(std::size_t)>& rank_of,
                        bool barnes_hut_start, std::vector<TreeAcrossRanksCounts>* counts = nullptr,
                        const std::vector<Vec3>* moved = nullptr, bool* loose = nullptr) {
  GravityTree whole(built.x, built.m, built.eps, c.tree);
  Sources s = built;
  if (moved) {
    s.x = *moved;
    whole.refit(s.x, s.m, s.eps);
    if (loose) *loose = whole.loose();
  }
  std::vector<double> a_old(s.x.size(), kNoOldAcceleration);
  if (!barnes_hut_start) {
    std::vector<GravityTarget> all(s.x.size());
    for (std::size_t i = 0; i < s.x.size(); ++i) all[i] = {s.x[i], s.eps[i], kNoOldAcceleration, std::int64_t(i)};
    std::vector<GravityResult> first(s.x.size());
    whole.accelerate(all, c.walk, first);
    for (std::size_t i = 0; i < s.x.size(); ++i) a_old[i] = norm(first[i].acceleration);
  }
  const Vec3 lo = whole.nodes()[0].centre - 0.5 * Vec3{whole.nodes()[0].side, whole.nodes()[0].side, whole.nodes()[0].side};
  const double cell = whole.nodes()[0].side / 6.0;
  auto cell_of = [&](const Vec3& x) {
    int k = 0;
    for (int d = 0; d < 3; ++d) k = 6 * k + std::clamp(static_cast<int>((x[d] - lo[d]) / cell), 0, 5);
    return k;
  };
  std::vector<int> owner(s.x.size());
  for (std::size_t i = 0; i < s.x.size(); ++i) owner[i] = rank_of(i);
  if (counts) counts->assign(static_cast<std::size_t>(ranks), {});
  ThreadRanks threads(ranks);
  std::vector<std::size_t> checked(static_cast<std::size_t>(ranks), 0);
  threads.run([&](ThreadRanks::Messages& messages) {
    const int r = messages.rank();
    std::vector<std::size_t> mine;  // global indices, increasing
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if (owner[i] == r) mine.push_back(i);
    std::vector<Vec3> x;
    std::vector<double> m, eps;
    std::vector<std::uint64_t> places;
    for (const std::size_t i : mine) {
      x.push_back(built.x[i]);
      m.push_back(s.m[i]);
      eps.push_back(s.eps[i]);
      places.push_back(i);
    }
    // Batches by cell, in cell order; targets carry local (here) and global (whole) indices.
    std::vector<std::vector<GravityTarget>> local(216), global(216);
    for (std::size_t k = 0; k < mine.size(); ++k) {
      const std::size_t i = mine[k];
      if (i % 2) continue;
      const int b = cell_of(s.x[i]);
      local[static_cast<std::size_t>(b)].push_back({s.x[i], s.eps[i], a_old[i], std::int64_t(k)});
      global[static_cast<std::size_t>(b)].push_back({s.x[i], s.eps[i], a_old[i], std::int64_t(i)});
    }
    std::vector<TargetBatch> batches;
    for (const auto& b : local) batches.push_back({b});
    TreeAcrossRanks across(messages, RankSources::of_arrays(x, m, eps, places), c.tree, c.walk);
    if (moved) {
      for (std::size_t k = 0; k < mine.size(); ++k) x[k] = s.x[mine[k]];
      across.refit(messages, RankSources::of_arrays(x, m, eps, places));
      if (loose) {
        EXPECT_EQ(across.loose(), *loose);
      }
    }
    const GravityTree tree = across.tree_for(messages, batches);
    if (counts) (*counts)[static_cast<std::size_t>(r)] = across.counts();
    for (std::size_t b = 0; b < local.size(); ++b) {
      std::vector<GravityResult> here(local[b].size()), there(global[b].size());
      tree.accelerate(local[b], c.walk, here);
      whole.accelerate(global[b], c.walk, there);
      for (std::size_t t = 0; t < here.size(); ++t) {
        // Bitwise: EXPECT_EQ on doubles compares exactly.
        EXPECT_EQ(here[t].acceleration.x, there[t].acceleration.x) << "rank " << r << " batch " << b << " target " << t;
        EXPECT_EQ(here[t].acceleration.y, there[t].acceleration.y);
        EXPECT_EQ(here[t].acceleration.z, there[t].acceleration.z);
        EXPECT_EQ(here[t].potential, there[t].potential);
        EXPECT_EQ(here[t].node_interactions, there[t].node_interactions);
        EXPECT_EQ(here[t].particle_interactions, there[t].particle_interactions);
      }
      checked[static_cast<std::size_t>(r)] += here.size();
    }
  });
  std::size_t total = 0;
  for (const std::size_t n : checked) total += n;
  EXPECT_EQ(total, (s.x.size() + 1) / 2);
}

// Slabs along x (a domain cut), and an interleaving that puts several ranks in every node.
std::function<int(std::size_t)> slabs(const Sources& s, int ranks, double box) {
  return [&s, ranks, box](std::size_t i) { return std::min(ranks - 1, static_cast<int>(s.x[i].x / box * ranks)); };
}

Case open_case(OpeningCriterion criterion) {
  Case c;
  c.walk.criterion = criterion;
  return c;
}

Case periodic_case() {
  Case c;
  c.tree.periodic = true;
  c.tree.box_size = 1.0;
  c.walk.split = GravitySplit{1.25 / 16.0};
  return c;
}

}  // namespace

TEST(TreeAcrossRanks, OpenTreeGivesOneRanksForcesOnOneToFourRanks) {
  const Sources s = clustered(3000, 1.0, 11);
  for (const auto criterion : {OpeningCriterion::gadget2_monopole, OpeningCriterion::relative_quadrupole})
    for (int ranks : {1, 2, 3, 4}) {
      SCOPED_TRACE(testing::Message() << ranks << " ranks");
      expect_same_forces(s, open_case(criterion), ranks, slabs(s, ranks, 1.0), false);
    }
  // The first force of a run: Barnes-Hut, no |a_old|.
  expect_same_forces(s, open_case(OpeningCriterion::gadget2_monopole), 3, slabs(s, 3, 1.0), true);
}

TEST(TreeAcrossRanks, SourcesInterleavedAcrossRanksShareEveryNode) {
  // Every node holds several ranks' sources: the top reaches down to gathered leaves.
  const Sources s = clustered(1200, 1.0, 5);
  std::vector<TreeAcrossRanksCounts> counts;
  expect_same_forces(s, open_case(OpeningCriterion::gadget2_monopole), 3, [](std::size_t i) { return int(i % 3); },
                     false, &counts);
  for (const auto& c : counts) {
    EXPECT_GT(c.gathered_nodes, 20);  // 33 here
    EXPECT_GT(c.top_nodes, c.gathered_nodes);
  }
}

TEST(TreeAcrossRanks, PeriodicTreePMGivesOneRanksShortRange) {
  const Sources s = clustered(3000, 1.0, 23);
  for (int ranks : {2, 4}) {
    SCOPED_TRACE(testing::Message() << ranks << " ranks");
    expect_same_forces(s, periodic_case(), ranks, slabs(s, ranks, 1.0), false);
  }
}

TEST(TreeAcrossRanks, RanksReceiveOnlyWhatTheirWalksOpen) {
  // With a short range cut off at 0.28 of the box, a slab's walks open only the nodes near it.
  const Sources s = clustered(3000, 1.0, 23);
  std::vector<TreeAcrossRanksCounts> counts;
  expect_same_forces(s, periodic_case(), 4, slabs(s, 4, 1.0), false, &counts);
  for (const auto& c : counts) {
    EXPECT_GT(c.sources_received, 0);
    EXPECT_LT(c.sources_received, 3 * 3000 / 4);  // far less than every other rank's sources
    EXPECT_GT(c.own_subtrees, 0);
  }
  // A rank with no source and no target still takes part.
  expect_same_forces(s, open_case(OpeningCriterion::gadget2_monopole), 3,
                     [&s](std::size_t i) { return s.x[i].x < 0.5 ? 0 : 2; }, false);
}

TEST(TreeAcrossRanks, AWalkBeyondTheBatchesItWasAssembledForThrows) {
  // Rank 0 assembles for no target, so the other rank sends only its subtrees' roots; a walk
  // from inside the other rank's clump then opens one, which is not here.
  const Sources s = clustered(2000, 1.0, 3);
  ThreadRanks threads(2);
  bool threw = false;
  threads.run([&](ThreadRanks::Messages& messages) {
    const int r = messages.rank();
    std::vector<Vec3> x;
    std::vector<double> m, eps;
    std::vector<std::uint64_t> places;
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if ((s.x[i].x < 0.5) == (r == 0)) {
        x.push_back(s.x[i]);
        m.push_back(s.m[i]);
        eps.push_back(s.eps[i]);
        places.push_back(i);
      }
    const Case c = open_case(OpeningCriterion::gadget2_monopole);
    TreeAcrossRanks across(messages, RankSources::of_arrays(x, m, eps, places), c.tree, c.walk);
    GravityTree tree = across.tree_for(messages, {});
    EXPECT_THROW(tree.refit(x, m, eps), std::logic_error);  // assembled trees are assembled anew
    if (r != 0) return;
    const GravityTarget stray{{0.7, 0.6, 0.45}, 0.002, kNoOldAcceleration, -1};
    EXPECT_THROW(tree.accelerate(stray, c.walk), std::logic_error);
    threw = true;
  });
  EXPECT_TRUE(threw);
  // Places must follow the sources' order (the run's order).
  ThreadRanks one(1);
  EXPECT_THROW(one.run([&](ThreadRanks::Messages& messages) {
    const std::vector<Vec3> x{{0, 0, 0}, {1, 1, 1}};
    const std::vector<double> m{1, 1}, eps{0.1, 0.1};
    const std::vector<std::uint64_t> places{1, 0};
    const TreeAcrossRanks across(messages, RankSources::of_arrays(x, m, eps, places), TreeConfig{}, WalkConfig{});
  }),
               std::invalid_argument);
}

TEST(TreeAcrossRanks, RefittedAfterADriftItGivesOneRanksRefittedForces) {
  const Sources s = clustered(3000, 1.0, 17);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> step(0.0, 1.0);
  for (const double size : {1e-3, 0.05}) {
    SCOPED_TRACE(testing::Message() << "drift " << size);
    std::vector<Vec3> moved = s.x;
    for (Vec3& x : moved)
      for (int d = 0; d < 3; ++d) x[d] = std::clamp(x[d] + size * step(rng), 0.0, 1.0 - 1e-12);
    bool loose = false;
    expect_same_forces(s, open_case(OpeningCriterion::gadget2_monopole), 3, slabs(s, 3, 1.0), false, nullptr, &moved,
                       &loose);
    // A small drift leaves the cubes within twice their built sides; a large one does not.
    EXPECT_EQ(loose, size > 0.01);
    expect_same_forces(s, periodic_case(), 2, slabs(s, 2, 1.0), false, nullptr, &moved);
  }
}

TEST(TreeAcrossRanks, ARankWithoutSourcesWalksTheTreeAnotherRankHoldsWhole) {
  // Every source on rank 0, so the whole tree is one subtree held there; rank 1 has none and
  // walks targets of its own (not sources), in two batches, on what rank 0 sends it.
  const Sources s = clustered(1500, 1.0, 9);
  const Case c = open_case(OpeningCriterion::gadget2_monopole);
  const GravityTree whole(s.x, s.m, s.eps, c.tree);
  std::vector<std::vector<GravityTarget>> batches(2);
  for (std::size_t i = 0; i < 60; ++i)
    batches[i % 2].push_back({s.x[i * 7] + Vec3{1e-3, -2e-3, 5e-4}, 0.003, 0.1 * static_cast<double>(i + 1), -1});
  ThreadRanks threads(2);
  std::size_t compared = 0;
  threads.run([&](ThreadRanks::Messages& messages) {
    const int r = messages.rank();
    std::vector<std::uint64_t> places;
    if (r == 0)
      for (std::size_t i = 0; i < s.x.size(); ++i) places.push_back(i);
    const RankSources mine = r == 0 ? RankSources::of_arrays(s.x, s.m, s.eps, places) : RankSources{};
    TreeAcrossRanks across(messages, mine, c.tree, c.walk);
    std::vector<TargetBatch> mine_to_walk;
    if (r == 1)
      for (const auto& b : batches) mine_to_walk.push_back({b});
    const GravityTree& tree = across.tree_for(messages, mine_to_walk);
    if (r != 1) return;
    EXPECT_GT(across.counts().nodes_received, 1);
    for (const auto& b : batches) {
      std::vector<GravityResult> here(b.size()), there(b.size());
      tree.accelerate(b, c.walk, here);
      whole.accelerate(b, c.walk, there);
      for (std::size_t t = 0; t < b.size(); ++t) {
        EXPECT_EQ(here[t].acceleration.x, there[t].acceleration.x) << t;
        EXPECT_EQ(here[t].acceleration.y, there[t].acceleration.y) << t;
        EXPECT_EQ(here[t].acceleration.z, there[t].acceleration.z) << t;
        EXPECT_EQ(here[t].potential, there[t].potential) << t;
        ++compared;
      }
    }
  });
  EXPECT_EQ(compared, 60u);
}
