// A listed leaf's particles sorted into a TreePM group's far and near lists, eight at a time where the processor allows.
#pragma once
#include <cstdint>

#include "core/Vec3.hpp"

namespace fountain::gravity {

// The group's box as the walk sees it, and the nearest-image shift that every particle of the
// leaf shares (the walk checks that the leaf lies wholly within half a box of the group's
// centre, so each particle's nearest image is its leaf's): a particle's offset from the
// centre along x is (x - centre.x) + shift.x, as GravityTree::image computes it.
struct LeafScanBox {
  Vec3 centre, half, shift;
  double h_max = 0.0;    // the group's largest spline length
  double cutoff2 = 0.0;  // the TreePM cut-off, squared
};

// For the `count` particles from tree position `first` (positions and spline lengths in tree
// order): with d2 the squared distance from the particle to the box, a particle with
// d2 <= cutoff2 goes to `far` if d2 > 0 and d2 >= max(h_max, its spline length)^2, otherwise
// to `near`; others are dropped. Tree positions are appended at far[*far_count] and
// near[*near_count] in order, and the counts advanced; both lists must hold 8 entries past
// their final counts. The AVX-512 loop and the portable one give the same lists.
void scan_leaf(const Vec3* positions, const double* splines, std::int32_t first, std::int32_t count,
               const LeafScanBox& box, std::int32_t* far, std::int32_t* far_count, std::int32_t* near,
               std::int32_t* near_count);
void scan_leaf_portable(const Vec3* positions, const double* splines, std::int32_t first, std::int32_t count,
                        const LeafScanBox& box, std::int32_t* far, std::int32_t* far_count, std::int32_t* near,
                        std::int32_t* near_count);

}  // namespace fountain::gravity
