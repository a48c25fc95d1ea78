// Zoom initial conditions against COSMOLOGY.md C10.12: nested noise, mass and coverage, the unigrid limit, the parent's field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <vector>

#include "ics/CosmologicalBox.hpp"
#include "ics/LagrangianPerturbation.hpp"
#include "ics/WhiteNoise.hpp"
#include "ics/ZoomInitialConditions.hpp"

namespace fountain::ics {
namespace {

std::size_t at(int n, int i, int j, int k) { return (static_cast<std::size_t>(i) * n + j) * n + k; }

// The mean over each block of 8 children of a level's noise grid (N = n children per side).
std::vector<double> block_means(const std::vector<double>& w, int n) {
  const int m = n / 2;
  std::vector<double> out(static_cast<std::size_t>(m) * m * m, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) out[at(m, i / 2, j / 2, k / 2)] += w[at(n, i, j, k)] / 8.0;
  return out;
}

TEST(NestedNoise, BlocksKeepTheCoarseNoiseAndChildrenAreWhite) {
  const std::uint64_t seed = 3;
  // One level: raw noise.
  const std::vector<double> raw = nested_noise(seed, 4, 4);
  for (std::size_t c = 0; c < raw.size(); ++c) ASSERT_EQ(raw[c], white_noise(seed, 4, c));
  // Each refinement keeps block means at the parent's value / sqrt(8).
  const std::vector<double> w3 = nested_noise(seed, 3, 3), w4 = nested_noise(seed, 3, 4), w5 = nested_noise(seed, 3, 5);
  double worst = 0.0;
  const std::vector<double> m4 = block_means(w4, 16), m5 = block_means(w5, 32);
  for (std::size_t c = 0; c < m4.size(); ++c) worst = std::max(worst, std::fabs(m4[c] - w3[c] / std::sqrt(8.0)));
  for (std::size_t c = 0; c < m5.size(); ++c) worst = std::max(worst, std::fabs(m5[c] - w4[c] / std::sqrt(8.0)));
  // The children's variance and their siblings' covariance.
  double var = 0.0, cov = 0.0;
  int pairs = 0;
  for (int i = 0; i < 32; i += 2)
    for (int j = 0; j < 32; ++j)
      for (int k = 0; k < 32; ++k) {
        cov += w5[at(32, i, j, k)] * w5[at(32, i + 1, j, k)];
        ++pairs;
      }
  for (double v : w5) var += v * v;
  var /= static_cast<double>(w5.size());
  cov /= pairs;
  std::printf("nested noise: block means off by %.1e; variance %.4f, sibling covariance %.4f\n", worst, var, cov);
  EXPECT_LT(worst, 1e-14);
  EXPECT_NEAR(var, 1.0, 0.03);
  EXPECT_LT(std::fabs(cov), 0.03);
}

CosmologicalBoxParams zoom_params(bool gas) {
  CosmologicalBoxParams p;
  p.box = 20.0;
  p.a_start = 0.02;
  p.seed = 7;
  p.cosmology = {0.3, 0.7, 0.04, 0.7};
  p.gas = gas;
  return p;
}

// Each finest-level cell is covered by exactly one particle (its own, its parent-level block's
// or its coarsest block's), and the masses add up to Omega_m rho_crit0 L^3.
TEST(ZoomIcs, MassAndCoverage) {
  const ZoomLevels levels{3, 4, 5};
  const CosmologicalBoxParams p = zoom_params(true);
  std::vector<std::uint8_t> region(16 * 16 * 16, 0);
  region[at(16, 15, 0, 7)] = region[at(16, 0, 0, 7)] = region[at(16, 0, 1, 7)] = 1;  // across the box's face
  const Units units;
  const CosmologicalBox z = make_zoom(p, levels, region, units);
  std::vector<int> covered(32 * 32 * 32, 0);
  double mass = 0.0;
  std::map<Species, std::size_t> count;
  for (std::size_t q = 0; q < z.dark_matter.size(); ++q) {
    mass += z.dark_matter.mass[q];
    ++count[z.dark_matter.species[q]];
    const std::uint64_t id = z.dark_matter.id[q] - 1;
    const int level = id >> 42 ? 3 : id >> 41 ? 4 : 5;
    const std::uint64_t cell = id & ((std::uint64_t{1} << 40) - 1);
    const int n = 1 << level, r = 1 << (5 - level);
    const int i = static_cast<int>(cell / (n * n)), j = static_cast<int>(cell / n % n), k = static_cast<int>(cell % n);
    for (int a = 0; a < r; ++a)
      for (int b = 0; b < r; ++b)
        for (int c = 0; c < r; ++c) ++covered[at(32, i * r + a, j * r + b, k * r + c)];
  }
  for (double m : z.gas.mass) mass += m;
  for (int c : covered) ASSERT_EQ(c, 1);
  const double expected = 0.3 * 3.0 * 100.0 * 100.0 / (8.0 * std::numbers::pi * units.gravitational_constant()) * 8000.0;
  std::printf("zoom: %zu fine dark matter, %zu gas, %zu low-resolution; mass %.12e (expected %.12e)\n", count[Species::DarkMatter],
              z.gas.size(), count[Species::LowResDarkMatter], mass, expected);
  EXPECT_EQ(count[Species::DarkMatter], 3u * 8u);
  EXPECT_EQ(z.gas.size(), 3u * 8u);
  EXPECT_NEAR(mass / expected, 1.0, 1e-12);
}

// A region covering the whole box with one level is the unigrid box, bit for bit.
TEST(ZoomIcs, WholeBoxAtOneLevelIsTheUnigridBox) {
  CosmologicalBoxParams p = zoom_params(true);
  p.level = 4;
  const Units units;
  const CosmologicalBox unigrid = make_cosmological_box(p, units);
  const CosmologicalBox zoom = make_zoom(p, {4, 4, 4}, std::vector<std::uint8_t>(16 * 16 * 16, 1), units);
  ASSERT_EQ(zoom.dark_matter.size(), unigrid.dark_matter.size());
  ASSERT_EQ(zoom.gas.size(), unigrid.gas.size());
  for (std::size_t c = 0; c < unigrid.dark_matter.size(); ++c) {
    ASSERT_EQ(zoom.dark_matter.x[c], unigrid.dark_matter.x[c]);
    ASSERT_EQ(zoom.dark_matter.v[c], unigrid.dark_matter.v[c]);
    ASSERT_EQ(zoom.dark_matter.id[c], unigrid.dark_matter.id[c]);
    ASSERT_EQ(zoom.gas.x[c], unigrid.gas.x[c]);
    ASSERT_EQ(zoom.gas.u[c], unigrid.gas.u[c]);
  }
}

// COSMOLOGY.md C10.12: the parent level's field and the zoom's finest field averaged onto the
// parent level, both Gaussian-smoothed over 3 parent cells, correlate >= 0.995 and differ by at
// most 10% rms (32^3 -> 64^3 in 26.6 Mpc/h).
TEST(ZoomIcs, FieldAveragedToTheParentLevelFollowsTheParent) {
  CosmologicalBoxParams p = zoom_params(false);
  p.box = 26.6;
  const int lp = 5, lmax = 6, np = 32, nf = 64;
  const double smoothing = 3.0 * p.box / np;
  auto gauss = [&](double k) { return std::exp(-0.5 * k * k * smoothing * smoothing); };
  p.level = lp;
  const std::vector<double> parent = real_field(linear_density_of(nested_noise(p.seed, lp - 1, lp), p), gauss);
  CosmologicalBoxParams fine = p;
  fine.level = lmax;
  const std::vector<double> zoom = real_field(linear_density_of(nested_noise(p.seed, lp - 1, lmax), fine), [](double) { return 1.0; });
  std::vector<double> averaged(parent.size(), 0.0);
  for (int i = 0; i < nf; ++i)
    for (int j = 0; j < nf; ++j)
      for (int k = 0; k < nf; ++k) averaged[at(np, i / 2, j / 2, k / 2)] += zoom[at(nf, i, j, k)] / 8.0;
  const std::vector<double> smoothed = real_field(forward_transform(averaged, np, p.box), gauss);
  double sa = 0.0, sb = 0.0, sab = 0.0, diff = 0.0;
  for (std::size_t c = 0; c < parent.size(); ++c) {
    sa += parent[c] * parent[c];
    sb += smoothed[c] * smoothed[c];
    sab += parent[c] * smoothed[c];
    diff += (parent[c] - smoothed[c]) * (parent[c] - smoothed[c]);
  }
  const double correlation = sab / std::sqrt(sa * sb), rms = std::sqrt(diff / sa);
  std::printf("zoom field on the parent level: correlation %.4f, rms difference %.1f%%\n", correlation, 100.0 * rms);
  EXPECT_GE(correlation, 0.995);
  EXPECT_LE(rms, 0.10);
}

}  // namespace
}  // namespace fountain::ics
