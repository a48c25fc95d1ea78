#include "gravity/LeafScan.hpp"

#include <algorithm>
#include <cmath>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "core/CpuFeatures.hpp"

namespace fountain::gravity {

// The walk's own arithmetic (gap, and the squared gap to the box), operation by operation;
// this file is compiled without fused multiply-adds, so the AVX-512 loop rounds alike.
void scan_leaf_portable(const Vec3* positions, const double* splines, std::int32_t first, std::int32_t count,
                        const LeafScanBox& box, std::int32_t* far, std::int32_t* far_count, std::int32_t* near,
                        std::int32_t* near_count) {
  std::int32_t f = *far_count, m = *near_count;
  for (std::int32_t k = first; k < first + count; ++k) {
    const Vec3& x = positions[k];
    const double px = std::max(std::fabs((x.x - box.centre.x) + box.shift.x) - box.half.x, 0.0);
    const double py = std::max(std::fabs((x.y - box.centre.y) + box.shift.y) - box.half.y, 0.0);
    const double pz = std::max(std::fabs((x.z - box.centre.z) + box.shift.z) - box.half.z, 0.0);
    const double d2 = px * px + py * py + pz * pz;
    const double hp = std::max(box.h_max, splines[k]);
    const bool keep = d2 <= box.cutoff2;
    // Strictly beyond (d2 > 0): a particle inside the box may be one of the targets.
    const bool is_far = d2 > 0.0 && d2 >= hp * hp;
    far[f] = k;
    near[m] = k;
    f += (keep & is_far) ? 1 : 0;
    m += (keep & !is_far) ? 1 : 0;
  }
  *far_count = f;
  *near_count = m;
}

#if defined(__x86_64__) && defined(__GNUC__)
namespace {
// The gap between the box and eight particles along one axis (zero in lanes not live).
__attribute__((target("avx512f,avx512vl"))) inline __m512d gap(__m512d x, __m512d centre, __m512d shift,
                                                              __m512d half, __mmask8 live) {
  const __m512d offset = _mm512_add_pd(_mm512_sub_pd(x, centre), shift);
  return _mm512_maskz_max_pd(live, _mm512_sub_pd(_mm512_abs_pd(offset), half), _mm512_setzero_pd());
}

__attribute__((target("avx512f,avx512vl"))) void scan_leaf_avx512(const Vec3* positions, const double* splines,
                                                                   std::int32_t first, std::int32_t count,
                                                                   const LeafScanBox& box, std::int32_t* far,
                                                                   std::int32_t* far_count, std::int32_t* near,
                                                                   std::int32_t* near_count) {
  const __m512d cx = _mm512_set1_pd(box.centre.x), cy = _mm512_set1_pd(box.centre.y), cz = _mm512_set1_pd(box.centre.z);
  const __m512d sx = _mm512_set1_pd(box.shift.x), sy = _mm512_set1_pd(box.shift.y), sz = _mm512_set1_pd(box.shift.z);
  const __m512d hx = _mm512_set1_pd(box.half.x), hy = _mm512_set1_pd(box.half.y), hz = _mm512_set1_pd(box.half.z);
  const __m512d h_max = _mm512_set1_pd(box.h_max), cutoff2 = _mm512_set1_pd(box.cutoff2);
  const __m512d zero = _mm512_setzero_pd();
  // Vec3 is three doubles: the eight particles' x at strides of three.
  const __m256i stride = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
  const __m256i step = _mm256_set1_epi32(1);
  std::int32_t f = *far_count, m = *near_count;
  __m256i index = _mm256_add_epi32(_mm256_set1_epi32(first), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  for (std::int32_t k = first; k < first + count; k += 8) {
    const std::int32_t left = first + count - k;
    const __mmask8 live = left >= 8 ? static_cast<__mmask8>(0xff) : static_cast<__mmask8>((1u << left) - 1u);
    const double* base = &positions[k].x;
    const __m512d x = _mm512_mask_i32gather_pd(zero, live, stride, base, 8);
    const __m512d y = _mm512_mask_i32gather_pd(zero, live, stride, base + 1, 8);
    const __m512d z = _mm512_mask_i32gather_pd(zero, live, stride, base + 2, 8);
    const __m512d px = gap(x, cx, sx, hx, live), py = gap(y, cy, sy, hy, live), pz = gap(z, cz, sz, hz, live);
    const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(px, px), _mm512_mul_pd(py, py)), _mm512_mul_pd(pz, pz));
    const __m512d hp = _mm512_maskz_max_pd(live, h_max, _mm512_maskz_loadu_pd(live, splines + k));
    const __mmask8 keep = _mm512_mask_cmp_pd_mask(live, d2, cutoff2, _CMP_LE_OQ);
    const __mmask8 is_far = _mm512_cmp_pd_mask(d2, zero, _CMP_GT_OQ) & _mm512_cmp_pd_mask(d2, _mm512_mul_pd(hp, hp), _CMP_GE_OQ);
    const auto to_far = static_cast<__mmask8>(keep & is_far), to_near = static_cast<__mmask8>(keep & ~is_far);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(far + f), _mm256_maskz_compress_epi32(to_far, index));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(near + m), _mm256_maskz_compress_epi32(to_near, index));
    f += __builtin_popcount(to_far);
    m += __builtin_popcount(to_near);
    index = _mm256_add_epi32(index, _mm256_slli_epi32(step, 3));
  }
  *far_count = f;
  *near_count = m;
}
}  // namespace

void scan_leaf(const Vec3* positions, const double* splines, std::int32_t first, std::int32_t count,
               const LeafScanBox& box, std::int32_t* far, std::int32_t* far_count, std::int32_t* near,
               std::int32_t* near_count) {
  if (cpu_has_avx512())
    scan_leaf_avx512(positions, splines, first, count, box, far, far_count, near, near_count);
  else
    scan_leaf_portable(positions, splines, first, count, box, far, far_count, near, near_count);
}
#else
void scan_leaf(const Vec3* positions, const double* splines, std::int32_t first, std::int32_t count,
               const LeafScanBox& box, std::int32_t* far, std::int32_t* far_count, std::int32_t* near,
               std::int32_t* near_count) {
  scan_leaf_portable(positions, splines, first, count, box, far, far_count, near, near_count);
}
#endif

}  // namespace fountain::gravity
