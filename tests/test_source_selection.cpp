// The TreePM walk's per-target selection of particle sources: every path keeps exactly the sources a plain test keeps.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "gravity/SourceSelection.hpp"

namespace fountain::gravity {
namespace {

TEST(SourceSelection, KeepsExactlyTheSourcesWithinTheCutOffInOrderOnEveryPath) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
  const float r_cut2 = 0.25f;
  int kept_total = 0;
  for (int count : {0, 1, 7, 15, 16, 17, 31, 33, 250}) {
    for (int fields : {3, 4, 8}) {
      const auto n = static_cast<std::size_t>(count);
      std::vector<std::vector<float>> in(8, std::vector<float>(n));
      for (int f = 0; f < 8; ++f)
        for (std::size_t k = 0; k < n; ++k) in[static_cast<std::size_t>(f)][k] = uni(rng);
      // On the cut-off itself (0.5^2 is exact): not kept, the test being strict.
      if (count > 3) in[0][3] = 0.5f, in[1][3] = 0.0f, in[2][3] = 0.0f;
      const float* in_ptr[8];
      for (int f = 0; f < 8; ++f) in_ptr[f] = in[static_cast<std::size_t>(f)].data();
      std::vector<std::vector<float>> fast(8, std::vector<float>(n + 16)), portable(8, std::vector<float>(n + 16));
      float* fast_ptr[8];
      float* portable_ptr[8];
      for (int f = 0; f < 8; ++f) {
        fast_ptr[f] = fast[static_cast<std::size_t>(f)].data();
        portable_ptr[f] = portable[static_cast<std::size_t>(f)].data();
      }
      std::vector<float> r2;
      std::vector<std::int32_t> kept;
      const int m_fast = select_within(SourceFields{in_ptr, fast_ptr, fields, count}, 0.0f, 0.0f, 0.0f, r_cut2, r2, kept);
      const int m_portable =
          select_within_portable(SourceFields{in_ptr, portable_ptr, fields, count}, 0.0f, 0.0f, 0.0f, r_cut2, r2, kept);
      std::vector<std::size_t> expected;
      for (std::size_t k = 0; k < n; ++k) {
        const float dx = 0.0f - in[0][k], dy = 0.0f - in[1][k], dz = 0.0f - in[2][k];
        if (dx * dx + dy * dy + dz * dz < r_cut2) expected.push_back(k);
      }
      kept_total += static_cast<int>(expected.size());
      ASSERT_EQ(m_fast, static_cast<int>(expected.size())) << "count " << count << " fields " << fields;
      ASSERT_EQ(m_portable, static_cast<int>(expected.size())) << "count " << count << " fields " << fields;
      for (std::size_t i = 0; i < expected.size(); ++i)
        for (int f = 0; f < fields; ++f) {
          const auto fi = static_cast<std::size_t>(f);
          EXPECT_EQ(fast[fi][i], in[fi][expected[i]]) << "count " << count << " field " << f << " kept " << i;
          EXPECT_EQ(portable[fi][i], in[fi][expected[i]]) << "count " << count << " field " << f << " kept " << i;
        }
    }
  }
  EXPECT_GT(kept_total, 50);  // about 6.5% of the sources lie within the cut-off
  RecordProperty("avx512_path", select_within_is_avx512() ? "yes" : "no");
}

}  // namespace
}  // namespace fountain::gravity
