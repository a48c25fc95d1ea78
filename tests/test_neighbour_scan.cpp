// The SPH loops' inner neighbour search: every path lists exactly the candidates a plain test keeps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "hydro/NeighbourScan.hpp"

namespace fountain {
namespace {

TEST(NeighbourScan, ListsExactlyTheCandidatesWithinReachOnEveryPath) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  int kept_total = 0;
  for (std::size_t n : {0, 1, 2, 7, 8, 9, 15, 16, 17, 63, 200, 333}) {
    std::vector<double> x(n), y(n), z(n), h2(n);
    for (std::size_t k = 0; k < n; ++k) x[k] = uni(rng), y[k] = uni(rng), z[k] = uni(rng), h2[k] = 0.5 * (1 + uni(rng));
    const Vec3 p{0.1 * uni(rng), 0.1 * uni(rng), 0.1 * uni(rng)};
    for (bool own : {false, true}) {
      const double reach2 = 0.3;
      std::vector<double> r2_fast(n), r2_portable(n);
      std::vector<std::uint32_t> fast(n + hydro::kScanSlack), portable(n + hydro::kScanSlack);
      const std::size_t m_fast = hydro::scan_within(x.data(), y.data(), z.data(), h2.data(), n, p, reach2, own,
                                                    r2_fast.data(), fast.data());
      const std::size_t m_portable = hydro::scan_within_portable(x.data(), y.data(), z.data(), h2.data(), n, p,
                                                                 reach2, own, r2_portable.data(), portable.data());
      std::vector<std::uint32_t> expected;
      for (std::size_t k = 0; k < n; ++k) {
        const double dx = p.x - x[k], dy = p.y - y[k], dz = p.z - z[k];
        const double r2 = dx * dx + dy * dy + dz * dz;
        EXPECT_EQ(r2_fast[k], r2) << "n " << n << " k " << k;  // bitwise: the lists feed the sums
        EXPECT_EQ(r2_portable[k], r2) << "n " << n << " k " << k;
        if (r2 < reach2 || (own && r2 < h2[k])) expected.push_back(static_cast<std::uint32_t>(k));
      }
      kept_total += static_cast<int>(expected.size());
      ASSERT_EQ(m_fast, expected.size()) << "n " << n << " own " << own;
      ASSERT_EQ(m_portable, expected.size()) << "n " << n << " own " << own;
      for (std::size_t m = 0; m < expected.size(); ++m) {
        EXPECT_EQ(fast[m], expected[m]);
        EXPECT_EQ(portable[m], expected[m]);
      }
    }
  }
  EXPECT_GT(kept_total, 100);
  RecordProperty("avx512_path", hydro::scan_within_is_avx512() ? "yes" : "no");
}

TEST(NeighbourScan, KeepsExactlyTheCandidatesNearABoxOnEveryPath) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  int kept_total = 0;
  for (std::size_t n : {0, 1, 5, 8, 9, 16, 31, 250}) {
    std::vector<double> x(n), y(n), z(n), h2(n);
    std::vector<std::size_t> index(n);
    for (std::size_t k = 0; k < n; ++k)
      x[k] = uni(rng), y[k] = uni(rng), z[k] = uni(rng), h2[k] = 0.2 * (1 + uni(rng)), index[k] = 1000 + 3 * k;
    const Vec3 lo{-0.2, -0.1, 0.0}, hi{0.1, 0.2, 0.15};
    for (bool own : {false, true}) {
      const double reach2 = 0.16;
      const std::size_t room = n + hydro::kScanSlack;
      std::vector<double> fx(room), fy(room), fz(room), fh(room), px(room), py(room), pz(room), ph(room);
      std::vector<std::size_t> fi(room), pi(room);
      const hydro::CandidateView in{x.data(), y.data(), z.data(), h2.data(), index.data()};
      const std::size_t m_fast =
          hydro::scan_near_box(in, n, lo, hi, reach2, own, {fx.data(), fy.data(), fz.data(), fh.data(), fi.data()});
      const std::size_t m_portable = hydro::scan_near_box_portable(
          in, n, lo, hi, reach2, own, {px.data(), py.data(), pz.data(), ph.data(), pi.data()});
      std::vector<std::size_t> expected;
      for (std::size_t k = 0; k < n; ++k) {
        const double dx = std::max({0.0, lo.x - x[k], x[k] - hi.x});
        const double dy = std::max({0.0, lo.y - y[k], y[k] - hi.y});
        const double dz = std::max({0.0, lo.z - z[k], z[k] - hi.z});
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < reach2 || (own && d2 < h2[k])) expected.push_back(k);
      }
      kept_total += static_cast<int>(expected.size());
      ASSERT_EQ(m_fast, expected.size()) << "n " << n << " own " << own;
      ASSERT_EQ(m_portable, expected.size()) << "n " << n << " own " << own;
      for (std::size_t m = 0; m < expected.size(); ++m) {
        const std::size_t k = expected[m];
        EXPECT_EQ(fi[m], index[k]);
        EXPECT_EQ(pi[m], index[k]);
        EXPECT_EQ(fx[m], x[k]);
        EXPECT_EQ(py[m], y[k]);
        EXPECT_EQ(fz[m], z[k]);
        EXPECT_EQ(fh[m], h2[k]);
        EXPECT_EQ(px[m], x[k]);
        EXPECT_EQ(fy[m], y[k]);
        EXPECT_EQ(pz[m], z[k]);
        EXPECT_EQ(ph[m], h2[k]);
      }
    }
  }
  EXPECT_GT(kept_total, 100);
}

}  // namespace
}  // namespace fountain
