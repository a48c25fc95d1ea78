// The TreePM walk's selections of particle sources (a leaf's for its group, a group's for each target): every path keeps exactly the sources a plain test keeps.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "core/Vec3.hpp"
#include "gravity/LeafScan.hpp"
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

// With the blocks' boxes (bound_blocks), runs of sixteen beyond the cut-off are passed over
// unread: every path still keeps exactly the sources the plain test keeps, for targets inside,
// beside and on the cut-off from the boxes, including sources on the boxes' faces.
TEST(SourceSelection, BlockBoxesPassOverOnlyRunsWithNothingWithinTheCutOff) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<float> uni(-1.0f, 1.0f), blob(-0.05f, 0.05f);
  const float r_cut = 0.25f, r_cut2 = r_cut * r_cut;
  long long kept_total = 0, passed_over = 0, runs = 0;
  for (int count : {1, 15, 16, 17, 255, 256, 257, 600}) {
    const auto n = static_cast<std::size_t>(count);
    std::vector<std::vector<float>> in(8, std::vector<float>(n));
    // Runs of neighbouring sources, as a walk lists leaves: blobs of 5 to 12 about random centres.
    for (std::size_t k = 0; k < n;) {
      const float cx = uni(rng), cy = uni(rng), cz = uni(rng);
      const std::size_t end = std::min(n, k + 5 + rng() % 8);
      for (; k < end; ++k) in[0][k] = cx + blob(rng), in[1][k] = cy + blob(rng), in[2][k] = cz + blob(rng);
    }
    for (int f = 3; f < 8; ++f)
      for (std::size_t k = 0; k < n; ++k) in[static_cast<std::size_t>(f)][k] = uni(rng);
    std::vector<float> boxes;
    const int stride = bound_blocks(in[0].data(), in[1].data(), in[2].data(), count, boxes);
    ASSERT_EQ(stride % kSourceBlock, 0);
    ASSERT_GE(stride * kSourceBlock, count);
    // Targets: random ones, and ones exactly the cut-off beyond a box's face along x (the
    // box's gap is then r_cut, which the strict test drops, as it drops the face's source).
    std::vector<std::array<float, 3>> targets;
    for (int t = 0; t < 40; ++t) targets.push_back({uni(rng), uni(rng), uni(rng)});
    for (int b = 0; b * kSourceBlock < count; ++b) {
      const float hi_x = boxes[static_cast<std::size_t>(3 * stride + b)], lo_y = boxes[static_cast<std::size_t>(stride + b)];
      targets.push_back({hi_x + r_cut, lo_y, boxes[static_cast<std::size_t>(2 * stride + b)]});
      targets.push_back({hi_x + std::nextafter(r_cut, 0.0f), lo_y, boxes[static_cast<std::size_t>(2 * stride + b)]});
    }
    const float* in_ptr[8];
    for (int f = 0; f < 8; ++f) in_ptr[f] = in[static_cast<std::size_t>(f)].data();
    for (const auto& [xt, yt, zt] : targets) {
      std::vector<std::size_t> expected;
      for (std::size_t k = 0; k < n; ++k) {
        const float dx = xt - in[0][k], dy = yt - in[1][k], dz = zt - in[2][k];
        if (dx * dx + dy * dy + dz * dz < r_cut2) expected.push_back(k);
      }
      kept_total += static_cast<long long>(expected.size());
      for (int b = 0; b * kSourceBlock < count; ++b, ++runs) {
        bool any = false;
        for (std::size_t i : expected) any = any || static_cast<int>(i) / kSourceBlock == b;
        passed_over += any ? 0 : 1;
      }
      for (bool portable : {false, true}) {
        std::vector<std::vector<float>> out(8, std::vector<float>(n + 16));
        float* out_ptr[8];
        for (int f = 0; f < 8; ++f) out_ptr[f] = out[static_cast<std::size_t>(f)].data();
        std::vector<float> r2;
        std::vector<std::int32_t> kept;
        const SourceFields fields{in_ptr, out_ptr, 8, count, boxes.data(), stride};
        const int m = portable ? select_within_portable(fields, xt, yt, zt, r_cut2, r2, kept)
                               : select_within(fields, xt, yt, zt, r_cut2, r2, kept);
        ASSERT_EQ(m, static_cast<int>(expected.size())) << "count " << count << " portable " << portable;
        for (std::size_t i = 0; i < expected.size(); ++i)
          for (int f = 0; f < 8; ++f)
            ASSERT_EQ(out[static_cast<std::size_t>(f)][i], in[static_cast<std::size_t>(f)][expected[i]])
                << "count " << count << " field " << f << " kept " << i << " portable " << portable;
      }
    }
  }
  EXPECT_GT(kept_total, 300);
  EXPECT_GT(passed_over, runs / 2);  // the boxes have runs to pass over
}

// A leaf's particles against a group's box: each goes to the far list (beyond the box and
// beyond max(h_max, its spline length)), the near list (within that length, or inside the box),
// or neither (beyond the cut-off), in tree order, with the image shift added to every offset;
// the AVX-512 and portable loops agree, whatever the count's remainder of eight.
TEST(LeafScan, SortsALeafsParticlesAsThePlainTestsDo) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(-3.0, 3.0), len(0.0, 0.6);
  LeafScanBox box;
  box.centre = {10.0, -2.0, 0.5};
  box.half = {0.5, 0.25, 0.75};
  box.shift = {-16.0, 0.0, 16.0};
  box.h_max = 0.4;
  box.cutoff2 = 2.5 * 2.5;
  int far_total = 0, near_total = 0;
  for (int count : {0, 1, 5, 8, 9, 16, 23, 64}) {
    std::vector<Vec3> x(static_cast<std::size_t>(count + 3));
    std::vector<double> h(x.size());
    for (std::size_t k = 0; k < x.size(); ++k) {
      // Offsets from the centre once shifted, within +-3: inside, near, far and beyond.
      x[k] = {box.centre.x - box.shift.x + uni(rng), box.centre.y + uni(rng), box.centre.z - box.shift.z + uni(rng)};
      h[k] = len(rng);
    }
    // On the cut-off itself along x (kept: the test is d2 <= cutoff2), and a particle inside the box (near).
    if (count > 2) x[4].x = box.centre.x - box.shift.x + 0.5 + 2.5, x[4].y = box.centre.y, x[4].z = box.centre.z - box.shift.z;
    if (count > 3) x[5] = {box.centre.x - box.shift.x, box.centre.y, box.centre.z - box.shift.z};
    const std::int32_t first = 3;
    std::vector<std::int32_t> want_far, want_near;
    for (std::int32_t k = first; k < first + count; ++k) {
      const auto u = static_cast<std::size_t>(k);
      const double gx = std::max(std::fabs((x[u].x - box.centre.x) + box.shift.x) - box.half.x, 0.0);
      const double gy = std::max(std::fabs((x[u].y - box.centre.y) + box.shift.y) - box.half.y, 0.0);
      const double gz = std::max(std::fabs((x[u].z - box.centre.z) + box.shift.z) - box.half.z, 0.0);
      const double d2 = gx * gx + gy * gy + gz * gz;
      const double hp = std::max(box.h_max, h[u]);
      if (d2 > box.cutoff2) continue;
      (d2 > 0.0 && d2 >= hp * hp ? want_far : want_near).push_back(k);
    }
    for (int path = 0; path < 2; ++path) {
      // Lists already holding entries: the scan appends.
      std::vector<std::int32_t> far(2 + static_cast<std::size_t>(count) + 8, -7), near(1 + static_cast<std::size_t>(count) + 8, -7);
      std::int32_t n_far = 2, n_near = 1;
      (path == 0 ? scan_leaf : scan_leaf_portable)(x.data(), h.data(), first, count, box, far.data(), &n_far,
                                                   near.data(), &n_near);
      ASSERT_EQ(n_far - 2, static_cast<std::int32_t>(want_far.size())) << count << " path " << path;
      ASSERT_EQ(n_near - 1, static_cast<std::int32_t>(want_near.size())) << count << " path " << path;
      EXPECT_EQ(far[0], -7);
      EXPECT_EQ(near[0], -7);
      EXPECT_TRUE(std::equal(want_far.begin(), want_far.end(), far.begin() + 2)) << count;
      EXPECT_TRUE(std::equal(want_near.begin(), want_near.end(), near.begin() + 1)) << count;
      if (count > 2) {
        EXPECT_NE(std::find(far.begin() + 2, far.begin() + n_far, 4), far.begin() + n_far) << "on the cut-off";
      }
      if (count > 3) {
        EXPECT_NE(std::find(near.begin() + 1, near.begin() + n_near, 5), near.begin() + n_near) << "inside";
      }
    }
    far_total += static_cast<int>(want_far.size());
    near_total += static_cast<int>(want_near.size());
  }
  // Every class was met.
  EXPECT_GT(far_total, 20);
  EXPECT_GT(near_total, 5);
  std::printf("leaf scan: %d far, %d near; AVX-512 path %s\n", far_total, near_total,
              select_within_is_avx512() ? "taken" : "not available here");
}

}  // namespace
}  // namespace fountain::gravity
