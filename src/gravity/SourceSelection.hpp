// A target's particle sources within the TreePM cut-off, picked from its group's list sixteen at a time where the processor allows.
#pragma once
#include <cstdint>
#include <vector>

namespace fountain::gravity {

// Sources as `fields` arrays of floats (x, y, z first, then any others, 3 <= fields <= 8),
// `count` of them. The selection keeps, in list order, the sources with
// (xt - x)^2 + (yt - y)^2 + (zt - z)^2 < r_cut2 (each product and sum rounded alone) and
// writes their fields to `out`, which must hold 16 floats past `count`. Returns how many.
struct SourceFields {
  const float* const* in;
  float* const* out;
  int fields, count;
};

// The portable loops: distances, a branch-free compaction of indices into `kept`, then the
// kept sources' fields. r2 and kept are scratch.
int select_within_portable(const SourceFields& s, float xt, float yt, float zt, float r_cut2, std::vector<float>& r2,
                           std::vector<std::int32_t>& kept);
// AVX-512 (compress stores) where the processor has it, otherwise the portable loops: the
// same sources in the same order either way.
int select_within(const SourceFields& s, float xt, float yt, float zt, float r_cut2, std::vector<float>& r2,
                  std::vector<std::int32_t>& kept);
bool select_within_is_avx512();

}  // namespace fountain::gravity
