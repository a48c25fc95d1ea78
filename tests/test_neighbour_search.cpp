// The gas searches beyond the SPH loops (within a radius; k nearest of a kind) against a check of every particle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <vector>

#include "space/NeighbourSearch.hpp"

namespace fountain {
namespace {

// Squared nearest-image distance in a box of side L (L = 0: open).
double distance2(const Vec3& a, const Vec3& b, double L) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    double d = std::fabs(a[k] - b[k]);
    if (L > 0.0) d = std::min(d, L - d);
    d2 += d * d;
  }
  return d2;
}
double distance(const Vec3& a, const Vec3& b, double L) { return std::sqrt(distance2(a, b, L)); }

struct ClusteredGas {
  GasParticles gas;
  CollisionlessParticles dm;
  Space space;
  double box;
};

// Clustered gas (half in one clump), cut into cells of up to 32 particles.
ClusteredGas make(bool periodic, unsigned seed) {
  ClusteredGas s{{}, {}, Space(SpaceConfig{}), 1.0};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, s.box);
  std::normal_distribution<double> N(0.0, 0.05);
  const std::size_t n = 1500;
  s.gas.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k)
      s.gas.x[i][k] = i % 2 ? U(rng) : std::clamp(0.9 + N(rng), 0.0, std::nextafter(s.box, 0.0));
    s.gas.h[i] = 0.04;
    s.gas.mass[i] = 1.0;
    s.gas.id[i] = i;
  }
  SpaceConfig config;
  config.periodic = periodic;
  config.box_size = {s.box, s.box, s.box};
  config.split_size = 32;
  s.space = Space(config);
  s.space.rebuild(s.gas, s.dm);
  return s;
}

class NeighbourSearch : public ::testing::TestWithParam<bool> {};

TEST_P(NeighbourSearch, WithinARadiusFindsExactlyTheParticlesEveryPairCheckFinds) {
  const bool periodic = GetParam();
  ClusteredGas s = make(periodic, 7);
  const double L = periodic ? s.box : 0.0;
  for (std::size_t probe : {0ul, 1ul, 17ul, 600ul, 1499ul})
    for (double radius : {0.01, 0.07, 0.3}) {
      std::vector<std::size_t> found;
      for_each_within(s.space, s.gas, s.gas.x[probe], radius, [&](std::size_t j, const Vec3& dx, double r) {
        found.push_back(j);
        EXPECT_NEAR(r, distance(s.gas.x[j], s.gas.x[probe], L), 1e-12);
        EXPECT_NEAR(norm(dx), r, 1e-12);
      });
      std::vector<std::size_t> expected;
      for (std::size_t j = 0; j < s.gas.size(); ++j)
        if (distance(s.gas.x[j], s.gas.x[probe], L) < radius) expected.push_back(j);
      std::sort(found.begin(), found.end());
      EXPECT_EQ(found, expected) << "probe " << probe << ", radius " << radius;
    }
}

TEST_P(NeighbourSearch, KNearestOfAKindAreTheNearestInIndexOrderOnTies) {
  const bool periodic = GetParam();
  ClusteredGas s = make(periodic, 11);
  const double L = periodic ? s.box : 0.0;
  auto odd = [](std::size_t j) { return j % 2 == 1; };
  for (std::size_t probe : {0ul, 3ul, 400ul, 1498ul})
    for (std::size_t k : {1ul, 10ul, 64ul})
      for (double max_radius : {0.0, 0.05}) {
        const auto found = nearest(s.space, s.gas, s.gas.x[probe], probe, k,
                                   max_radius, [&](std::size_t j) { return odd(s.gas.id[j]); });
        std::vector<std::tuple<double, std::size_t>> all;
        for (std::size_t j = 0; j < s.gas.size(); ++j) {
          const double r2 = distance2(s.gas.x[j], s.gas.x[probe], L);
          if (j != probe && odd(s.gas.id[j]) && (max_radius <= 0.0 || r2 <= max_radius * max_radius))
            all.emplace_back(r2, j);
        }
        std::sort(all.begin(), all.end());
        std::vector<std::size_t> expected;
        for (std::size_t m = 0; m < std::min(k, all.size()); ++m) expected.push_back(std::get<1>(all[m]));
        EXPECT_EQ(found, expected) << "probe " << probe << ", k " << k << ", max radius " << max_radius;
      }
}

INSTANTIATE_TEST_SUITE_P(OpenAndPeriodic, NeighbourSearch, ::testing::Bool());

}  // namespace
}  // namespace fountain
