#include "gravity/SourceSelection.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "core/CpuFeatures.hpp"

namespace fountain::gravity {

int select_within_portable(const SourceFields& s, float xt, float yt, float zt, float r_cut2, std::vector<float>& r2,
                           std::vector<std::int32_t>& kept) {
  const auto n = static_cast<std::size_t>(s.count);
  const float *x = s.in[0], *y = s.in[1], *z = s.in[2];
  r2.resize(n);
  kept.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const float dx = xt - x[k], dy = yt - y[k], dz = zt - z[k];
    r2[k] = dx * dx + dy * dy + dz * dz;
  }
  std::size_t m = 0;
  for (std::size_t k = 0; k < n; ++k) {
    kept[m] = static_cast<std::int32_t>(k);
    m += r2[k] < r_cut2 ? 1 : 0;
  }
  for (int f = 0; f < s.fields; ++f)
    for (std::size_t i = 0; i < m; ++i) s.out[f][i] = s.in[f][static_cast<std::size_t>(kept[i])];
  return static_cast<int>(m);
}

#if defined(__x86_64__) && defined(__GNUC__)
namespace {
// The distances as the portable loop computes them (this file is compiled without fused
// multiply-adds, so the same bits), the test as one mask, and each field's kept lanes
// compressed into a register and stored whole.
__attribute__((target("avx512f,avx512vl"))) int select_within_avx512(const SourceFields& s, float xt, float yt,
                                                                    float zt, float r_cut2) {
  const __m512 px = _mm512_set1_ps(xt), py = _mm512_set1_ps(yt), pz = _mm512_set1_ps(zt);
  const __m512 reach = _mm512_set1_ps(r_cut2);
  const int count = s.count;
  int m = 0;
  for (int k = 0; k < count; k += 16) {
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
    m += __builtin_popcount(keep);
  }
  return m;
}
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
