// A target's particle sources within the TreePM cut-off, picked from its group's list sixteen at a time where the processor allows.
#pragma once
#include <cstdint>
#include <vector>

namespace fountain::gravity {

// Sources as `fields` arrays of floats (x, y, z first, then any others, 3 <= fields <= 8),
// `count` of them. The selection keeps, in list order, the sources with
// (xt - x)^2 + (yt - y)^2 + (zt - z)^2 < r_cut2 (each product and sum rounded alone) and
// writes their fields to `out`, which must hold 16 floats past `count`. Returns how many.
// `blocks`, if given, holds bound_blocks()'s boxes of the sources: a run of sixteen whose box
// lies at (xt - hi)^2 + ... >= r_cut2 (rounded as the sources' distances are) is passed over
// unread. Rounding is monotone, so no source in it could have been kept: the same list.
struct SourceFields {
  const float* const* in;
  float* const* out;
  int fields, count;
  const float* blocks = nullptr;
  int block_stride = 0;  // between the boxes' six coordinate arrays (bound_blocks)
};

// Sources per block of the selection's boxes: AVX-512's float width.
inline constexpr int kSourceBlock = 16;
// The bounding box of each run of kSourceBlock sources into `boxes` (resized): six arrays,
// lo x, lo y, lo z, hi x, hi y, hi z, each of the returned stride (the number of runs rounded
// up to kSourceBlock, the padding boxes empty). A group's list comes leaf by leaf in the
// walk's depth-first order, so a run is a few neighbouring leaves, and each target of a group
// lies beyond the cut-off of most runs (63% on a uniform box).
int bound_blocks(const float* x, const float* y, const float* z, int count, std::vector<float>& boxes);

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
