// The group finders over particles spread across ranks (ranks run as threads) against one process's catalogues, bit for bit, and friends-of-friends against brute-force linking.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "ThreadRanks.hpp"
#include "groups/FofAcrossRanks.hpp"
#include "groups/HopAcrossRanks.hpp"
#include "groups/SlabsAcrossRanks.hpp"

namespace fountain::groups {
namespace {

using test_ranks::ThreadRanks;

// Dark matter in clumps (some across the box's corner) over a uniform background, and gas
// (a non-linking type) scattered about the same places; IDs shuffled so that they follow no
// position.
ParticleSet clustered_set(std::size_t n, double box, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<std::uint64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = 1000 + 7 * i;
  std::shuffle(ids.begin(), ids.end(), rng);
  ParticleSet set;
  std::vector<Vec3> centres;
  for (int c = 0; c < 12; ++c) centres.push_back(c % 4 == 0 ? Vec3{} : Vec3{u(rng) * box, u(rng) * box, u(rng) * box});
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 x;
    if (i % 3 == 0) {
      x = {u(rng) * box, u(rng) * box, u(rng) * box};
    } else {
      const std::size_t c = (i / 5) % centres.size();
      x = centres[c] + Vec3{g(rng), g(rng), g(rng)} * (0.005 * box * static_cast<double>(1 + c % 4));
    }
    if (box > 0.0)
      for (int k = 0; k < 3; ++k) x[k] -= box * std::floor(x[k] / box);
    const int type = i % 4 == 3 ? 0 : 1;
    set.push_back(x, {g(rng), g(rng), g(rng)}, type == 0 ? 0.2 : 1.0 + 0.25 * static_cast<double>(i % 3), ids[i], type);
  }
  return set;
}

// The particles dealt to `ranks` ranks at random (not by position).
std::vector<ParticleSet> dealt(const ParticleSet& all, int ranks, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<ParticleSet> out(static_cast<std::size_t>(ranks));
  for (std::size_t i = 0; i < all.size(); ++i)
    out[rng() % static_cast<std::size_t>(ranks)].push_back(all.x[i], all.v[i], all.mass[i], all.id[i], all.type[i]);
  return out;
}

FofParameters parameters(double box) {
  FofParameters p;
  p.box = box;
  p.linking_length = 0.02;
  p.G = 1.0;
  p.softening = 0.004;
  p.overdensity = 1e6;  // about 200 times the mean density of the sets below
  p.min_members = 20;
  return p;
}

// `find(mine, ranks)` on every rank (ranks as threads): rank 0's catalogue; the others' must be empty.
template <class Find>
auto on_ranks(const std::vector<ParticleSet>& shares, Find&& find) {
  ThreadRanks threads(static_cast<int>(shares.size()));
  decltype(find(shares[0], nullptr)) on_rank0;
  threads.run([&](ThreadRanks::Messages& m) {
    auto c = find(shares[static_cast<std::size_t>(m.rank())], &m);
    if (m.rank() == 0) on_rank0 = std::move(c);
    else EXPECT_TRUE(c.groups.empty());
  });
  return on_rank0;
}

GroupCatalogue across(const std::vector<ParticleSet>& shares, const FofParameters& p) {
  return on_ranks(shares, [&](const ParticleSet& mine, Collectives* ranks) { return find_fof_groups_across_ranks(mine, p, ranks); });
}

void expect_same(const GroupCatalogue& a, const GroupCatalogue& b) {
  ASSERT_EQ(a.groups.size(), b.groups.size());
  EXPECT_EQ(a.member_id, b.member_id);
  EXPECT_EQ(a.member_type, b.member_type);
  for (std::size_t g = 0; g < a.groups.size(); ++g) {
    const Group &x = a.groups[g], &y = b.groups[g];
    SCOPED_TRACE(::testing::Message() << "group " << g);
    EXPECT_EQ(x.mass, y.mass);
    EXPECT_EQ(x.mass_by_type, y.mass_by_type);
    EXPECT_EQ(x.count_by_type, y.count_by_type);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(x.centre_of_mass[k], y.centre_of_mass[k]);
      EXPECT_EQ(x.potential_minimum[k], y.potential_minimum[k]);
      EXPECT_EQ(x.velocity[k], y.velocity[k]);
    }
    EXPECT_EQ(x.m200, y.m200);
    EXPECT_EQ(x.r200, y.r200);
    EXPECT_EQ(x.members, y.members);
  }
}

// The dark matter's components by brute force (O(N^2)), as sets of IDs with at least
// min_members members.
std::set<std::set<std::uint64_t>> brute_force_groups(const ParticleSet& s, const FofParameters& p) {
  std::vector<std::size_t> dm;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.type[i] == 1) dm.push_back(i);
  std::vector<int> seen(dm.size(), 0);
  std::set<std::set<std::uint64_t>> out;
  for (std::size_t a = 0; a < dm.size(); ++a) {
    if (seen[a]) continue;
    std::vector<std::size_t> queue{a};
    seen[a] = 1;
    for (std::size_t q = 0; q < queue.size(); ++q)
      for (std::size_t b = 0; b < dm.size(); ++b) {
        if (seen[b]) continue;
        Vec3 d = s.x[dm[b]] - s.x[dm[queue[q]]];
        if (p.box > 0.0)
          for (int k = 0; k < 3; ++k) d[k] -= p.box * std::nearbyint(d[k] / p.box);
        if (dot(d, d) < p.linking_length * p.linking_length) seen[b] = 1, queue.push_back(b);
      }
    if (queue.size() < p.min_members) continue;
    std::set<std::uint64_t> ids;
    for (std::size_t k : queue) ids.insert(s.id[dm[k]]);
    out.insert(ids);
  }
  return out;
}

TEST(FofAcrossRanks, OneToFourRanksGiveOneRanksCatalogue) {
  for (const double box : {1.0, 0.0}) {
    SCOPED_TRACE(box > 0.0 ? "periodic" : "open");
    const ParticleSet all = clustered_set(6000, box > 0.0 ? box : 1.0, 3);
    const FofParameters p = parameters(box);
    const GroupCatalogue alone = find_fof_groups_across_ranks(all, p, nullptr);
    ASSERT_GE(alone.groups.size(), 8u);
    // Membership by brute force: the dark matter of each group is a component of its own.
    std::set<std::set<std::uint64_t>> found;
    for (const Group& g : alone.groups) {
      std::set<std::uint64_t> ids;
      for (std::uint32_t m : g.members)
        if (alone.member_type[m] == 1) ids.insert(alone.member_id[m]);
      found.insert(ids);
    }
    EXPECT_EQ(found, brute_force_groups(all, p));
    std::uint64_t gas = 0;
    for (const Group& g : alone.groups) gas += g.count_by_type[0];
    EXPECT_GT(gas, 100u);  // gas attached
    EXPECT_GT(alone.groups[0].m200, 0.0);
    for (int ranks = 1; ranks <= 4; ++ranks) {
      SCOPED_TRACE(::testing::Message() << ranks << " ranks");
      expect_same(across(dealt(all, ranks, 10 + static_cast<std::uint64_t>(ranks)), p), alone);
    }
  }
}

// Most particles in one clump narrower than a linking length in x: the slabs of equal count
// are thinner than the linking length, so copies go to ranks beyond the next slab; a rank may
// hold nothing at all.
TEST(FofAcrossRanks, SlabsThinnerThanTheLinkingLength) {
  ParticleSet all;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const FofParameters p = parameters(1.0);
  for (std::uint64_t i = 0; i < 3000; ++i) {
    const bool clump = i % 10 != 0;
    const Vec3 x = clump ? Vec3{0.5 + 0.8 * p.linking_length * u(rng), 0.5 + 0.1 * u(rng), 0.5 + 0.1 * u(rng)}
                         : Vec3{u(rng), u(rng), u(rng)};
    all.push_back(x, {}, 1.0, 5000 - i, 1);
  }
  const GroupCatalogue alone = find_fof_groups_across_ranks(all, p, nullptr);
  ASSERT_GE(alone.groups.size(), 1u);
  for (int ranks = 2; ranks <= 4; ++ranks) {
    SCOPED_TRACE(::testing::Message() << ranks << " ranks");
    expect_same(across(dealt(all, ranks, 40 + static_cast<std::uint64_t>(ranks)), p), alone);
  }
  // Every particle on one rank, none on the others.
  std::vector<ParticleSet> lopsided(3);
  lopsided[2] = all;
  expect_same(across(lopsided, p), alone);
}

HopCatalogue hop_across(const std::vector<ParticleSet>& shares, const HopParameters& p) {
  return on_ranks(shares, [&](const ParticleSet& mine, Collectives* ranks) {
    // Gas carries hidden stars of a tenth of its mass.
    std::vector<double> hidden(mine.size());
    for (std::size_t i = 0; i < mine.size(); ++i) hidden[i] = mine.type[i] == 0 ? 0.1 * mine.mass[i] : 0.0;
    return find_hop_groups_across_ranks(mine, hidden, p, ranks);
  });
}

void expect_same(const HopCatalogue& a, const HopCatalogue& b) {
  ASSERT_EQ(a.groups.size(), b.groups.size());
  EXPECT_EQ(a.member_id, b.member_id);
  EXPECT_EQ(a.member_type, b.member_type);
  EXPECT_EQ(a.member_density, b.member_density);
  for (std::size_t g = 0; g < a.groups.size(); ++g) {
    const HopCatalogueGroup &x = a.groups[g], &y = b.groups[g];
    SCOPED_TRACE(::testing::Message() << "HOP group " << g);
    EXPECT_EQ(x.mass, y.mass);
    EXPECT_EQ(x.mass_by_type, y.mass_by_type);
    EXPECT_EQ(x.count_by_type, y.count_by_type);
    EXPECT_EQ(x.peak_density, y.peak_density);
    EXPECT_EQ(x.peak_member, y.peak_member);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(x.peak[k], y.peak[k]);
      EXPECT_EQ(x.centre_of_mass[k], y.centre_of_mass[k]);
      EXPECT_EQ(x.velocity[k], y.velocity[k]);
    }
    EXPECT_EQ(x.members, y.members);
  }
}

// Gas and stars in clumps over a background, some across the box's corner: HOP's groups on
// 1 to 4 ranks are one process's, with densities, peaks and centres to the bit; at the
// thresholds chosen the clumps are several groups, some merged through saddles, and the
// margins must widen in the sparse background.
TEST(HopAcrossRanks, OneToFourRanksGiveOneProcesssCatalogue) {
  for (const double box : {1.0, 0.0}) {
    SCOPED_TRACE(box > 0.0 ? "periodic" : "open");
    ParticleSet all = clustered_set(6000, 1.0, 12);
    for (std::size_t i = 0; i < all.size(); ++i) all.type[i] = i % 5 == 0 ? 4 : 0;
    HopParameters p;
    p.box = box;
    const double mean = 6000.0 * 0.5;  // about: masses 0.2 to 1.5
    p.delta_outer = 20.0 * mean, p.delta_saddle = 2.5 * p.delta_outer, p.delta_peak = 3.0 * p.delta_outer;
    std::vector<ParticleSet> one(1, all);
    const HopCatalogue alone = hop_across(one, p);
    ASSERT_GE(alone.groups.size(), 4u);
    std::size_t members = 0;
    for (const HopCatalogueGroup& g : alone.groups) members += g.members.size();
    EXPECT_GT(members, 1000u);
    EXPECT_LT(members, all.size() * 3 / 4);  // not the uniform third
    for (int ranks = 2; ranks <= 4; ++ranks) {
      SCOPED_TRACE(::testing::Message() << ranks << " ranks");
      expect_same(hop_across(dealt(all, ranks, 70 + static_cast<std::uint64_t>(ranks)), p), alone);
    }
  }
  // Every particle within one 4096th of the box in x: one slab holds them all, and the other
  // ranks own empty slabs.
  ParticleSet flat = clustered_set(3000, 1.0, 13);
  for (std::size_t i = 0; i < flat.size(); ++i) flat.x[i].x = 0.5 + 1e-4 * flat.x[i].x;
  HopParameters p;
  p.box = 1.0;
  p.delta_outer = 1e6, p.delta_saddle = 2.5e6, p.delta_peak = 3e6;
  const HopCatalogue alone = hop_across(std::vector<ParticleSet>(1, flat), p);
  ASSERT_GE(alone.groups.size(), 1u);
  expect_same(hop_across(dealt(flat, 3, 90), p), alone);
}

TEST(FofAcrossRanks, SumInAnyOrderIsTheSameForEverySplit) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> values(5000);
  for (double& v : values) v = std::exp(10.0 * u(rng));
  const double alone = sum_in_any_order(values, nullptr);
  long double exact = 0.0L;
  for (double v : values) exact += v;
  EXPECT_NEAR(alone / static_cast<double>(exact), 1.0, 1e-14);
  EXPECT_EQ(sum_in_any_order({1e100, 1.0, -1e100}, nullptr), 1.0);  // exact, not rounded per value
  for (int ranks = 2; ranks <= 4; ++ranks) {
    std::vector<std::vector<double>> share(static_cast<std::size_t>(ranks));
    std::shuffle(values.begin(), values.end(), rng);
    for (std::size_t i = 0; i < values.size(); ++i) share[rng() % share.size()].push_back(values[i]);
    ThreadRanks threads(ranks);
    threads.run([&](ThreadRanks::Messages& m) {
      EXPECT_EQ(sum_in_any_order(share[static_cast<std::size_t>(m.rank())], &m), alone);
      EXPECT_EQ(count_over_ranks(share[static_cast<std::size_t>(m.rank())].size(), &m), values.size());
    });
  }
}

}  // namespace
}  // namespace fountain::groups
