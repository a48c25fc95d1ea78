// Body-centred-cubic particle lattices, the usual start for SPH test problems.
#pragma once
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::ics {

// Points of a BCC lattice filling the box [lo, lo + size) with `cells` lattice cells along
// each side (two points per cell: a corner and the body centre).
std::vector<Vec3> bcc_lattice(const Vec3& lo, const Vec3& size, int cells_x, int cells_y, int cells_z);

}  // namespace fountain::ics
