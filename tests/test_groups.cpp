// Friends-of-friends against brute-force linking, the linking-length edge cases, and the group properties against analytic values.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "groups/FofCatalogue.hpp"
#include "groups/FriendsOfFriends.hpp"
#include "groups/Hop.hpp"
#include "groups/NearestNeighbours.hpp"

namespace fountain::groups {
namespace {

// b - a at the nearest image (box > 0) or plain.
Vec3 image(const Vec3& a, const Vec3& b, double box) {
  Vec3 d = b - a;
  if (box > 0.0)
    for (int k = 0; k < 3; ++k) d[k] -= box * std::nearbyint(d[k] / box);
  return d;
}

// O(N^2) linking: the smallest index of each point's component, by breadth-first search.
std::vector<std::uint32_t> brute_force_labels(const std::vector<Vec3>& x, double l, double box) {
  const std::size_t n = x.size();
  std::vector<std::uint32_t> label(n, UINT32_MAX);
  for (std::size_t s = 0; s < n; ++s) {
    if (label[s] != UINT32_MAX) continue;
    std::vector<std::size_t> queue{s};
    label[s] = static_cast<std::uint32_t>(s);
    for (std::size_t q = 0; q < queue.size(); ++q)
      for (std::size_t j = 0; j < n; ++j)
        if (label[j] == UINT32_MAX) {
          const Vec3 d = image(x[queue[q]], x[j], box);
          if (dot(d, d) < l * l) {
            label[j] = static_cast<std::uint32_t>(s);
            queue.push_back(j);
          }
        }
  }
  return label;
}

// Uniform points, plus (clustered) Plummer-like clumps across the box edges.
std::vector<Vec3> point_set(std::size_t n, double box, bool clustered, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> x;
  const std::size_t background = clustered ? n / 3 : n;
  for (std::size_t i = 0; i < background; ++i) x.push_back({u(rng) * box, u(rng) * box, u(rng) * box});
  while (x.size() < n) {
    // A clump whose centre may sit at the box's corner, so that it wraps.
    const Vec3 c = x.size() % 2 ? Vec3{0.0, 0.0, 0.0} : Vec3{u(rng) * box, u(rng) * box, u(rng) * box};
    const double size = 0.02 * box * (1.0 + 3.0 * u(rng));
    for (int k = 0; k < 200 && x.size() < n; ++k) {
      Vec3 p = c + Vec3{g(rng), g(rng), g(rng)} * size;
      for (int d = 0; d < 3; ++d) p[d] -= box * std::floor(p[d] / box);
      x.push_back(p);
    }
  }
  return x;
}

TEST(FriendsOfFriends, MatchesBruteForceLinking) {
  for (const bool clustered : {false, true})
    for (const double box : {0.0, 1.0}) {
      const std::vector<Vec3> x = point_set(3000, 1.0, clustered, clustered ? 7 : 3);
      // Near percolation for the uniform set (b = 0.85 of the spacing), smaller for the clumps.
      const double l = (clustered ? 0.25 : 0.85) / std::cbrt(3000.0);
      const std::vector<std::uint32_t> fast = link_friends(x, l, box);
      const std::vector<std::uint32_t> exact = brute_force_labels(x, l, box);
      std::size_t components = 0, largest = 0;
      std::map<std::uint32_t, std::size_t> sizes;
      for (std::uint32_t r : exact) ++sizes[r];
      for (const auto& [r, s] : sizes) ++components, largest = std::max(largest, s);
      std::printf("%s, %s: %zu components, the largest %zu\n", clustered ? "clustered" : "uniform",
                  box > 0.0 ? "periodic" : "open", components, largest);
      EXPECT_EQ(fast, exact);
      EXPECT_GT(largest, 50u);  // the test links something big
      EXPECT_LT(components, 2900u);
    }
}

TEST(FriendsOfFriends, SameLabelsOnOneAndTwoThreads) {
  const std::vector<Vec3> x = point_set(20000, 1.0, true, 11);
  const double l = 0.3 / std::cbrt(20000.0);
  std::vector<std::uint32_t> one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = link_friends(x, l, 1.0);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = link_friends(x, l, 1.0);
  }
  EXPECT_EQ(one, two);
}

// COSMOLOGY.md C10.11: the linking length's edge, the periodic boundary, a lattice, 31 members.
TEST(FriendsOfFriends, LinkingLengthEdgesAndLattice) {
  const double l = 0.05;
  // Pairs at 0.99 l link, at 1.01 l not.
  EXPECT_EQ(link_friends(std::vector<Vec3>{{0.5, 0.5, 0.5}, {0.5 + 0.99 * l, 0.5, 0.5}}, l, 1.0)[1], 0u);
  EXPECT_EQ(link_friends(std::vector<Vec3>{{0.5, 0.5, 0.5}, {0.5 + 1.01 * l, 0.5, 0.5}}, l, 1.0)[1], 1u);
  // Across the periodic boundary (and not in an open box).
  const std::vector<Vec3> edge{{0.3 * l, 0.2, 0.7}, {1.0 - 0.3 * l, 0.2, 0.7}};
  EXPECT_EQ(link_friends(edge, l, 1.0)[1], 0u);
  EXPECT_EQ(link_friends(edge, l, 0.0)[1], 1u);
  // A perfect lattice at b = 0.2 of its spacing: every point alone.
  std::vector<Vec3> lattice;
  const int n = 16;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) lattice.push_back(Vec3{i + 0.5, j + 0.5, k + 0.5} * (1.0 / n));
  const std::vector<std::uint32_t> alone = link_friends(lattice, 0.2 / n, 1.0);
  for (std::size_t i = 0; i < alone.size(); ++i) ASSERT_EQ(alone[i], i);
  // A chain of 31 primaries is dropped, of 32 kept, with a gas particle attached to the kept one.
  for (const int members : {31, 32}) {
    ParticleSet set;
    for (int k = 0; k < members; ++k) set.push_back({0.1 + 0.9 * l * k, 0.5, 0.5}, {}, 1.0, static_cast<std::uint64_t>(k + 1), 1);
    set.push_back({0.1, 0.5 + 0.9 * l, 0.5}, {}, 0.2, 100, 0);  // within l of the first
    set.push_back({0.1, 0.5 + 1.1 * l, 0.5}, {}, 0.2, 101, 0);  // beyond l of all
    FofParameters p;
    p.linking_length = l;
    p.box = 4.0;
    p.G = 1.0;
    p.softening = 0.01;
    const std::vector<Group> groups = find_fof_groups(set, p);
    if (members == 31) {
      EXPECT_TRUE(groups.empty());
    } else {
      ASSERT_EQ(groups.size(), 1u);
      EXPECT_EQ(groups[0].count_by_type[1], 32u);
      EXPECT_EQ(groups[0].count_by_type[0], 1u);
      EXPECT_DOUBLE_EQ(groups[0].mass, 32.2);
      EXPECT_EQ(set.id[groups[0].members.front()], 100u);  // by type, then ID
    }
  }
}

// A Plummer sphere of 20,000 dark matter particles (M = b = 1, r < 30 b) moving at a uniform
// velocity, centred on a corner of a periodic box so that it wraps: one group, its centre at
// the corner, its velocity exact, and R_200 and M_200 for a threshold density delta those of
// the profile, mean density 3 M / (4 pi (r^2 + b^2)^(3/2)) = delta.
TEST(FofCatalogue, PlummerSphereAcrossTheBoxEdge) {
  const double box = 100.0, M = 1.0, b = 1.0;
  const std::size_t n = 20000;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ParticleSet set;
  const Vec3 velocity{3.0, -1.0, 0.5};
  while (set.size() < n) {
    const double f = u(rng);
    const double r = b / std::sqrt(std::pow(f, -2.0 / 3.0) - 1.0);
    if (r > 30.0 * b) continue;
    const double z = 2.0 * u(rng) - 1.0, phi = 2.0 * std::numbers::pi * u(rng), s = std::sqrt(1.0 - z * z);
    Vec3 x{r * s * std::cos(phi), r * s * std::sin(phi), r * z};
    for (int k = 0; k < 3; ++k) x[k] -= box * std::floor(x[k] / box);
    set.push_back(x, velocity, M / n, set.size() + 1, 1);
  }
  FofParameters p;
  p.box = box;
  p.linking_length = 0.3;  // links the sphere out to several b
  p.G = 1.0;
  p.softening = 0.02;
  const double delta = 0.01;  // mean density 0.01: R = sqrt((3/(4 pi 0.01))^(2/3) - 1) = 2.707
  p.overdensity = delta;
  const std::vector<Group> groups = find_fof_groups(set, p);
  ASSERT_GE(groups.size(), 1u);
  const Group& g = groups[0];
  // The sphere cut at 30 b holds M: its profile is that of a Plummer sphere of M / M(<30 b).
  const double plummer = M * std::pow(30.0 * 30.0 + 1.0, 1.5) / std::pow(30.0, 3);
  const double r_exact = std::sqrt(std::pow(3.0 * plummer / (4.0 * std::numbers::pi * delta), 2.0 / 3.0) - b * b);
  const double m_exact = plummer * std::pow(r_exact, 3) / std::pow(r_exact * r_exact + b * b, 1.5);
  Vec3 c = g.potential_minimum, com = g.centre_of_mass;
  for (int k = 0; k < 3; ++k) c[k] -= box * std::nearbyint(c[k] / box), com[k] -= box * std::nearbyint(com[k] / box);
  std::printf("Plummer sphere: %zu members, centre %.3f b from the origin (centre of mass %.3f b); R_200 %.4f "
              "(exact %.4f), M_200 %.4f (exact %.4f)\n",
              g.members.size(), norm(c), norm(com), g.r200, r_exact, g.m200, m_exact);
  EXPECT_GT(g.members.size(), 15000u);
  EXPECT_LT(norm(c), 0.15 * b);  // the deepest particle of a discrete core
  EXPECT_LT(norm(com), 0.2 * b);
  EXPECT_NEAR(g.velocity.x, velocity.x, 1e-11);
  EXPECT_NEAR(g.velocity.y, velocity.y, 1e-11);
  EXPECT_NEAR(g.r200 / r_exact, 1.0, 0.02);
  EXPECT_NEAR(g.m200 / m_exact, 1.0, 0.03);
  // M_200 is the threshold density times the volume, by construction.
  EXPECT_NEAR(g.m200 / (4.0 / 3.0 * std::numbers::pi * std::pow(g.r200, 3) * delta), 1.0, 1e-12);
}

TEST(FofCatalogue, LinkingLengthOfThePapersZoom) {
  // COSMOLOGY.md C9.1: b = 0.2, mean high-resolution dark matter mass 6.7251e8 Msun/h,
  // (Omega_m - Omega_b) rho_crit0 = 0.27 x 2.775366e11: l = 0.04156 Mpc/h.
  EXPECT_NEAR(linking_length(0.2, 6.7251e8, 0.27 * 2.775366e11), 0.04156, 5e-5);
}

// ---- HOP ----------------------------------------------------------------------------------

double spline(double r, double h) {
  const double q = r / h, c = 1.0 / (std::numbers::pi * h * h * h);
  return q < 1.0 ? c * (1.0 - 1.5 * q * q + 0.75 * q * q * q) : q < 2.0 ? c * 0.25 * std::pow(2.0 - q, 3) : 0.0;
}

TEST(NearestNeighbours, MatchSortedDistances) {
  const std::vector<Vec3> x = point_set(2000, 1.0, true, 21);
  for (const double box : {0.0, 1.0}) {
    const NearestNeighbours tree(x, box);
    for (std::size_t i = 0; i < x.size(); i += 37) {
      std::vector<NearestNeighbours::Neighbour> all;
      for (std::size_t j = 0; j < x.size(); ++j) {
        const Vec3 d = image(x[i], x[j], box);
        all.push_back({dot(d, d), static_cast<std::uint32_t>(j)});
      }
      std::sort(all.begin(), all.end());
      const auto found = tree.nearest(x[i], 50);
      ASSERT_EQ(found.size(), 50u);
      for (std::size_t k = 0; k < 50; ++k) ASSERT_EQ(found[k].index, all[k].index) << "particle " << i << ", neighbour " << k;
    }
  }
}

// COSMOLOGY.md C10.10: HOP's densities against the O(N^2) sum of C9.2 step 1, to 1e-12.
TEST(Hop, DensitiesMatchBruteForce) {
  const std::vector<Vec3> x = point_set(1500, 1.0, true, 17);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  std::vector<double> m(x.size());
  for (double& mi : m) mi = u(rng);
  for (const double box : {0.0, 1.0}) {
    const int n_dens = 64;
    const std::vector<double> rho = hop_densities(x, m, n_dens, box);
    std::vector<double> h(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      std::vector<double> d2;
      for (std::size_t j = 0; j < x.size(); ++j) d2.push_back(dot(image(x[i], x[j], box), image(x[i], x[j], box)));
      std::nth_element(d2.begin(), d2.begin() + n_dens - 1, d2.end());
      h[i] = 0.5 * std::sqrt(d2[n_dens - 1]);
    }
    double worst = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      double exact = 0.0;
      for (std::size_t j = 0; j < x.size(); ++j) {
        const double r = norm(image(x[i], x[j], box));
        exact += 0.5 * m[j] * (spline(r, h[i]) + spline(r, h[j]));
      }
      worst = std::max(worst, std::fabs(rho[i] / exact - 1.0));
    }
    std::printf("HOP densities, %s box: largest relative difference from the direct sum %.1e\n", box > 0.0 ? "periodic" : "open", worst);
    EXPECT_LT(worst, 1e-12);
  }
}

// COSMOLOGY.md C10.10: two Plummer spheres (M = b = 1, 20,000 particles each within 30 b)
// 6 b apart. The saddle density between them is rho_s = 2 rho(3) = 1.50988e-3. With the
// thresholds (outer, saddle, peak) = (0.2, 0.5, 0.6) rho_s they are one group of the mass
// above the outer density, 2 M(< r_o) = 1.796; with (0.8, 2.0, 2.4) rho_s two, each of
// M(< 2.699) = 0.825 (M(< r) = M r^3 / (r^2 + b^2)^(3/2), rho(r_o) = delta_outer).
TEST(Hop, TwoPlummerSpheresMergeOrSplitAtTheSaddle) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> x;
  for (const double centre : {-3.0, 3.0}) {
    std::size_t made = 0;
    while (made < 20000) {
      const double r = 1.0 / std::sqrt(std::pow(u(rng), -2.0 / 3.0) - 1.0);
      if (r > 30.0) continue;
      const double z = 2.0 * u(rng) - 1.0, phi = 2.0 * std::numbers::pi * u(rng), s = std::sqrt(1.0 - z * z);
      x.push_back(Vec3{centre + r * s * std::cos(phi), r * s * std::sin(phi), r * z});
      ++made;
    }
  }
  const std::vector<double> m(x.size(), 1.0 / 20000.0);
  const double rho_s = 1.50988e-3;
  struct Case {
    double outer, saddle, peak;
    std::vector<double> masses;
  };
  for (const Case& c : {Case{0.2, 0.5, 0.6, {1.796}}, Case{0.8, 2.0, 2.4, {0.825, 0.825}}}) {
    HopParameters p;
    p.delta_outer = c.outer * rho_s;
    p.delta_saddle = c.saddle * rho_s;
    p.delta_peak = c.peak * rho_s;
    const HopResult r = find_hop_groups(x, m, p);
    std::printf("HOP at (%.1f, %.1f, %.1f) rho_s: %zu groups;", c.outer, c.saddle, c.peak, r.groups.size());
    for (const HopGroup& g : r.groups) std::printf(" %.4f (%zu particles)", g.mass, g.members.size());
    std::printf("\n");
    ASSERT_EQ(r.groups.size(), c.masses.size());
    for (std::size_t k = 0; k < c.masses.size(); ++k) EXPECT_NEAR(r.groups[k].mass / c.masses[k], 1.0, 0.06);
  }
}

TEST(Hop, SameGroupsOnOneAndTwoThreads) {
  const std::vector<Vec3> x = point_set(20000, 1.0, true, 23);
  const std::vector<double> m(x.size(), 1.0);
  HopParameters p;
  p.box = 1.0;
  p.delta_outer = 10.0 * 20000.0;  // ten times the mean density: the clumps
  p.delta_saddle = 2.5 * p.delta_outer;
  p.delta_peak = 3.0 * p.delta_outer;
  HopResult one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = find_hop_groups(x, m, p);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = find_hop_groups(x, m, p);
  }
  EXPECT_GT(one.groups.size(), 3u);
  EXPECT_EQ(one.density, two.density);
  EXPECT_EQ(one.group, two.group);
}

}  // namespace
}  // namespace fountain::groups
