// Exact sums (core/ExactSum.hpp) and the statistics taken with them (analysis/Diagnostics): the same double whatever the order and the split.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "analysis/Diagnostics.hpp"
#include "core/ExactSum.hpp"

namespace {

using fountain::ExactSum;

double sum_of(const std::vector<double>& v) {
  ExactSum s;
  for (double x : v) s.add(x);
  return s.value();
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(ExactSum, CancellationLeavesTheSmallTermsExactly) {
  // Naive summation in this order gives 0: 1e100 swallows 1 and 2^-60.
  EXPECT_EQ(sum_of({1e100, 1.0, -1e100}), 1.0);
  EXPECT_EQ(sum_of({1e300, std::ldexp(1.0, -60), 3.0, -1e300, -3.0}), std::ldexp(1.0, -60));
  EXPECT_EQ(sum_of({-2.5, 1e-300, 2.5, -1e-300}), 0.0);
  EXPECT_EQ(sum_of({}), 0.0);
  EXPECT_EQ(sum_of({-7.25}), -7.25);
  // Subnormals, and the largest finite doubles (carries past 2^1024 and back).
  const double tiny = std::ldexp(1.0, -1074);
  EXPECT_EQ(sum_of({tiny, tiny, tiny}), 3.0 * tiny);
  const double big = std::numeric_limits<double>::max();
  EXPECT_EQ(sum_of({big, big, -big}), big);
  EXPECT_EQ(sum_of({-big, -big, big, tiny}), -big);
}

TEST(ExactSum, RoundsTheExactTotalToNearest) {
  // 1 + 2^-53 is a tie, rounded to even (1); anything above it rounds up.
  EXPECT_EQ(sum_of({1.0, std::ldexp(1.0, -53)}), 1.0);
  EXPECT_EQ(sum_of({1.0, std::ldexp(1.0, -53), std::ldexp(1.0, -80)}), 1.0 + std::ldexp(1.0, -52));
  EXPECT_EQ(sum_of({1.0, std::ldexp(1.0, -53), std::ldexp(1.0, -1000)}), 1.0 + std::ldexp(1.0, -52));
  EXPECT_EQ(sum_of({-1.0, -std::ldexp(1.0, -53), -std::ldexp(1.0, -80)}), -1.0 - std::ldexp(1.0, -52));
  // Integers are summed exactly: 1 + 2 + ... + n.
  std::vector<double> n;
  for (int k = 1; k <= 100000; ++k) n.push_back(k);
  EXPECT_EQ(sum_of(n), 100000.0 * 100001.0 / 2.0);
}

TEST(ExactSum, AnyOrderAndAnySplitGiveTheSameBits) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> exponent(-30.0, 30.0);
  std::vector<double> v(20000);
  for (double& x : v) x = normal(rng) * std::pow(10.0, exponent(rng));
  const double reference = sum_of(v);
  // Against a sum in long double of the same values sorted by magnitude (close, not exact).
  std::vector<double> sorted = v;
  std::sort(sorted.begin(), sorted.end(), [](double a, double b) { return std::fabs(a) < std::fabs(b); });
  long double naive = 0.0L;
  for (double x : sorted) naive += x;
  EXPECT_NEAR(reference, static_cast<double>(naive), 1e-12 * std::fabs(reference) + 1e-10);
  double naive_double = 0.0;
  bool naive_order_matters = false;
  for (int trial = 0; trial < 8; ++trial) {
    std::shuffle(v.begin(), v.end(), rng);
    // Split in three at random points, summed apart and combined.
    std::uniform_int_distribution<std::size_t> cut(0, v.size());
    std::size_t a = cut(rng), b = cut(rng);
    if (a > b) std::swap(a, b);
    ExactSum parts[3];
    for (std::size_t i = 0; i < v.size(); ++i) parts[i < a ? 0 : (i < b ? 1 : 2)].add(v[i]);
    ExactSum total;
    for (int p : {2, 0, 1}) total.add(parts[p]);
    EXPECT_TRUE(same_bits(total.value(), reference)) << total.value() << " against " << reference;
    EXPECT_TRUE(same_bits(ExactSum::from_words(total.words().data()).value(), reference));
    double d = 0.0;
    for (double x : v) d += x;
    if (trial > 0 && !same_bits(d, naive_double)) naive_order_matters = true;
    naive_double = d;
  }
  // The test has teeth: plain summation of these values depends on their order.
  EXPECT_TRUE(naive_order_matters);
}

TEST(ExactSum, NonFiniteValuesGiveWhatADoubleSumGives) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(std::isnan(sum_of({1.0, std::nan(""), 2.0})));
  EXPECT_EQ(sum_of({1.0, inf, -1e300}), inf);
  EXPECT_EQ(sum_of({1.0, -inf}), -inf);
  EXPECT_TRUE(std::isnan(sum_of({inf, 1.0, -inf})));
  // ... and keep it through a split.
  ExactSum a, b;
  a.add(-inf);
  b.add(3.0);
  b.add(ExactSum::from_words(a.words().data()));
  EXPECT_EQ(b.value(), -inf);
}

// The statistics of a set summed run by run, and of the same runs in another order split as
// ranks split them (packed and combined), are the same bits.
TEST(DiagnosticsSum, PiecesInAnyOrderGiveTheWholeSumsBits) {
  using fountain::analysis::DiagnosticsSum;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  fountain::GasParticles gas;
  gas.resize(3000);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    gas.id[i] = i + 1;
    gas.mass[i] = 1e-3 * (0.5 + u01(rng));
    gas.mass_stars_hidden[i] = i % 3 == 0 ? 1e-4 * u01(rng) : 0.0;
    gas.reservoir[i] = i % 5 == 0 ? u01(rng) : 0.0;
    gas.promoted[i] = i % 7 == 0;
    gas.x[i] = {u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5};
    gas.v[i] = {u01(rng) - 0.5, 3.0 * (u01(rng) - 0.5), u01(rng) - 0.5};
    gas.u[i] = std::pow(10.0, 4.0 * u01(rng) - 2.0);
    gas.rho[i] = std::pow(10.0, 4.0 * u01(rng) - 4.0);
    gas.h[i] = 0.01 + 0.1 * u01(rng);
    gas.potential[i] = -2.0 * u01(rng);
    gas.time_bin[i] = static_cast<fountain::TimeBin>(20 + i % 9);
  }
  fountain::CollisionlessParticles dm;
  for (std::size_t i = 0; i < 2000; ++i)
    dm.push_back(10000 + i, i % 4 == 0 ? fountain::Species::Star : fountain::Species::DarkMatter, 5e-3 * (0.5 + u01(rng)),
                 {u01(rng), u01(rng), u01(rng)}, {u01(rng), -u01(rng), u01(rng)}, {u01(rng), -u01(rng), u01(rng)}, 0.0,
                 0);
  for (std::size_t i = 0; i < dm.size(); ++i) {
    dm.potential[i] = -u01(rng);
    dm.time_bin[i] = static_cast<fountain::TimeBin>(18 + i % 11);
  }
  const fountain::TemperatureOf temperature = [](double u) { return 1e4 * u; };
  const fountain::analysis::FigurePhases phases{4e4, 0.5};
  const double a = 0.37;
  // Runs as the leaves give them: gas in runs of 97, collisionless particles in runs of 61.
  struct Run {
    bool gas;
    std::size_t first, count;
  };
  std::vector<Run> runs;
  for (std::size_t f = 0; f < gas.size(); f += 97) runs.push_back({true, f, std::min<std::size_t>(97, gas.size() - f)});
  for (std::size_t f = 0; f < dm.size(); f += 61) runs.push_back({false, f, std::min<std::size_t>(61, dm.size() - f)});
  auto add_run = [&](DiagnosticsSum& sum, const Run& r) {
    if (r.gas) sum.add_gas(gas, r.first, r.count);
    else sum.add_collisionless(dm, r.first, r.count);
  };
  DiagnosticsSum whole(temperature, phases, a);
  for (const Run& r : runs) add_run(whole, r);
  const fountain::analysis::Diagnostics w = whole.result();
  EXPECT_GT(w.mass_hot, 0.0);
  EXPECT_GT(w.mass_cold, 0.0);
  EXPECT_GT(w.mass_warm, 0.0);
  EXPECT_GT(w.mass_stars, 0.0);

  // Three "ranks" take the runs in a shuffled order, dealt at random; rank 2 adds the others'.
  std::shuffle(runs.begin(), runs.end(), rng);
  DiagnosticsSum r0(temperature, phases, a), r1(temperature, phases, a), r2(temperature, phases, a);
  DiagnosticsSum* ranks[3] = {&r0, &r1, &r2};
  for (const Run& r : runs) add_run(*ranks[rng() % 3], r);
  r2.add_packed(r1.pack());
  r2.add_packed(r0.pack());
  const fountain::analysis::Diagnostics p = r2.result();
  for (auto [x, y] : {std::pair{w.mass_gas, p.mass_gas}, {w.mass_dark_matter, p.mass_dark_matter},
                      {w.mass_hot, p.mass_hot}, {w.mass_warm, p.mass_warm}, {w.mass_cold, p.mass_cold},
                      {w.mass_unbound, p.mass_unbound}, {w.thermal, p.thermal}, {w.kinetic, p.kinetic},
                      {w.potential, p.potential}, {w.mass_stars, p.mass_stars},
                      {w.mass_stars_hidden, p.mass_stars_hidden}, {w.mass_promoted_diffuse, p.mass_promoted_diffuse},
                      {w.reservoir, p.reservoir}, {w.h_min_gas, p.h_min_gas}})
    EXPECT_TRUE(same_bits(x, y)) << x << " against " << y;
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(same_bits(w.momentum[k], p.momentum[k]));
    EXPECT_TRUE(same_bits(w.angular_momentum[k], p.angular_momentum[k]));
  }
  EXPECT_EQ(w.time_bin_min, p.time_bin_min);
  EXPECT_EQ(w.time_bin_min, 18);
  // And the sums are those of the particles: the gas mass against a sum in long double; in
  // runs of one particle, in any order, the exact total.
  long double m = 0.0L;
  std::vector<double> masses;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    m += gas.mass[i];
    masses.push_back(gas.mass[i]);
  }
  EXPECT_NEAR(w.mass_gas, static_cast<double>(m), 1e-15 * w.mass_gas);
  DiagnosticsSum up(temperature, phases, a), down(temperature, phases, a);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    up.add_gas(gas, i, 1);
    down.add_gas(gas, gas.size() - 1 - i, 1);
  }
  EXPECT_TRUE(same_bits(up.result().mass_gas, sum_of(masses)));
  EXPECT_TRUE(same_bits(down.result().kinetic, up.result().kinetic));
  EXPECT_THROW(r2.add_packed(std::vector<char>(10)), std::logic_error);
}

}  // namespace
