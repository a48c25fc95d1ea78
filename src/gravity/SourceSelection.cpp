#include "gravity/SourceSelection.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <limits>

#include "core/CpuFeatures.hpp"

namespace fountain::gravity {

int bound_blocks(const float* x, const float* y, const float* z, int count, std::vector<float>& boxes) {
  const int blocks = (count + kSourceBlock - 1) / kSourceBlock;
  const int stride = (blocks + kSourceBlock - 1) / kSourceBlock * kSourceBlock;
  constexpr float inf = std::numeric_limits<float>::infinity();
  boxes.resize(6 * static_cast<std::size_t>(stride));
  float* lo[3] = {boxes.data(), boxes.data() + stride, boxes.data() + 2 * stride};
  float* hi[3] = {boxes.data() + 3 * stride, boxes.data() + 4 * stride, boxes.data() + 5 * stride};
  const float* in[3] = {x, y, z};
  for (int b = 0; b < stride; ++b) {
    const int begin = b * kSourceBlock, end = std::min(count, begin + kSourceBlock);
    for (int d = 0; d < 3; ++d) {
      float l = inf, h = -inf;  // an empty box lies beyond every cut-off
      for (int k = begin; k < end; ++k) l = std::min(l, in[d][k]), h = std::max(h, in[d][k]);
      lo[d][b] = l;
      hi[d][b] = h;
    }
  }
  return stride;
}

namespace {
// Whether block b of s lies at or beyond the cut-off: per axis the gap from the target to the
// box, no larger in magnitude than any of its sources' offsets once rounded, so its square
// sum is no larger than any of theirs.
bool block_beyond(const SourceFields& s, int b, float xt, float yt, float zt, float r_cut2) {
  if (s.blocks == nullptr) return false;
  const float* box = s.blocks + b;
  const int w = s.block_stride;
  const float gx = std::max({box[0] - xt, xt - box[3 * w], 0.0f}),
              gy = std::max({box[w] - yt, yt - box[4 * w], 0.0f}),
              gz = std::max({box[2 * w] - zt, zt - box[5 * w], 0.0f});
  return gx * gx + gy * gy + gz * gz >= r_cut2;
}
}  // namespace

int select_within_portable(const SourceFields& s, float xt, float yt, float zt, float r_cut2, std::vector<float>& r2,
                           std::vector<std::int32_t>& kept) {
  const auto n = static_cast<std::size_t>(s.count);
  const float *x = s.in[0], *y = s.in[1], *z = s.in[2];
  r2.resize(n);
  kept.resize(n);
  std::size_t m = 0;
  for (std::size_t begin = 0; begin < n; begin += kSourceBlock) {
    if (block_beyond(s, static_cast<int>(begin / kSourceBlock), xt, yt, zt, r_cut2)) continue;
    const std::size_t end = std::min(n, begin + kSourceBlock);
    for (std::size_t k = begin; k < end; ++k) {
      const float dx = xt - x[k], dy = yt - y[k], dz = zt - z[k];
      r2[k] = dx * dx + dy * dy + dz * dz;
    }
    for (std::size_t k = begin; k < end; ++k) {
      kept[m] = static_cast<std::int32_t>(k);
      m += r2[k] < r_cut2 ? 1 : 0;
    }
  }
  for (int f = 0; f < s.fields; ++f)
    for (std::size_t i = 0; i < m; ++i) s.out[f][i] = s.in[f][static_cast<std::size_t>(kept[i])];
  return static_cast<int>(m);
}

#if defined(__x86_64__) && defined(__GNUC__)
namespace {
// Inlined into the AVX-512 function (a call from it into code without the target costs
// AVX/SSE transitions: 8x the selection's time when the block test was such a call).
#define FOUNTAIN_AVX512 __attribute__((target("avx512f,avx512vl"), always_inline)) inline
// The sixteen sources from k: those within reach appended at out[f] + m; the new count. The
// distances as the portable loop computes them (this file is compiled without fused
// multiply-adds, so the same bits), the test as one mask, and each field's kept lanes
// compressed into a register and stored whole.
FOUNTAIN_AVX512 int select_block(const SourceFields& s, int k, __m512 px, __m512 py, __m512 pz, __m512 reach, int m) {
  const int count = s.count;
  const __mmask16 live =
      count - k >= 16 ? static_cast<__mmask16>(0xffff) : static_cast<__mmask16>((1u << (count - k)) - 1u);
  const __m512 x = _mm512_maskz_loadu_ps(live, s.in[0] + k), y = _mm512_maskz_loadu_ps(live, s.in[1] + k),
               z = _mm512_maskz_loadu_ps(live, s.in[2] + k);
  const __m512 dx = _mm512_sub_ps(px, x), dy = _mm512_sub_ps(py, y), dz = _mm512_sub_ps(pz, z);
  const __m512 d2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
  const __mmask16 keep = _mm512_mask_cmp_ps_mask(live, d2, reach, _CMP_LT_OQ);
  _mm512_storeu_ps(s.out[0] + m, _mm512_maskz_compress_ps(keep, x));
  _mm512_storeu_ps(s.out[1] + m, _mm512_maskz_compress_ps(keep, y));
  _mm512_storeu_ps(s.out[2] + m, _mm512_maskz_compress_ps(keep, z));
  for (int f = 3; f < s.fields; ++f)
    _mm512_storeu_ps(s.out[f] + m, _mm512_maskz_compress_ps(keep, _mm512_maskz_loadu_ps(live, s.in[f] + k)));
  return m + __builtin_popcount(keep);
}

// Sixteen boxes' gaps along one axis, as block_beyond takes one's.
// (The zero-masked max: GCC 12 warns of the plain one's undefined pass-through.)
FOUNTAIN_AVX512 __m512 box_gap(const float* lo, const float* hi, __m512 p) {
  constexpr __mmask16 all = 0xffff;
  const __m512 below = _mm512_sub_ps(_mm512_loadu_ps(lo), p), above = _mm512_sub_ps(p, _mm512_loadu_ps(hi));
  return _mm512_maskz_max_ps(all, _mm512_maskz_max_ps(all, below, above), _mm512_setzero_ps());
}

__attribute__((target("avx512f,avx512vl"))) int select_within_avx512(const SourceFields& s, float xt, float yt,
                                                                    float zt, float r_cut2) {
  const __m512 px = _mm512_set1_ps(xt), py = _mm512_set1_ps(yt), pz = _mm512_set1_ps(zt);
  const __m512 reach = _mm512_set1_ps(r_cut2);
  const int count = s.count;
  int m = 0;
  if (s.blocks == nullptr) {
    for (int k = 0; k < count; k += 16) m = select_block(s, k, px, py, pz, reach, m);
    return m;
  }
  // Sixteen blocks' boxes tested at once; the blocks within reach taken in order.
  const int w = s.block_stride;
  for (int b0 = 0; b0 * kSourceBlock < count; b0 += 16) {
    const float* box = s.blocks + b0;
    const __m512 gx = box_gap(box, box + 3 * w, px), gy = box_gap(box + w, box + 4 * w, py),
                 gz = box_gap(box + 2 * w, box + 5 * w, pz);
    const __m512 g2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(gx, gx), _mm512_mul_ps(gy, gy)), _mm512_mul_ps(gz, gz));
    unsigned within = _mm512_cmp_ps_mask(g2, reach, _CMP_LT_OQ);
    while (within != 0) {
      m = select_block(s, (b0 + __builtin_ctz(within)) * kSourceBlock, px, py, pz, reach, m);
      within &= within - 1;
    }
  }
  return m;
}
#undef FOUNTAIN_AVX512
}  // namespace

bool select_within_is_avx512() { return cpu_has_avx512(); }

int select_within(const SourceFields& s, float xt, float yt, float zt, float r_cut2, std::vector<float>& r2,
                  std::vector<std::int32_t>& kept) {
  if (cpu_has_avx512()) return select_within_avx512(s, xt, yt, zt, r_cut2);
  return select_within_portable(s, xt, yt, zt, r_cut2, r2, kept);
}
#else
bool select_within_is_avx512() { return false; }

int select_within(const SourceFields& s, float xt, float yt, float zt, float r_cut2, std::vector<float>& r2,
                  std::vector<std::int32_t>& kept) {
  return select_within_portable(s, xt, yt, zt, r_cut2, r2, kept);
}
#endif

}  // namespace fountain::gravity
