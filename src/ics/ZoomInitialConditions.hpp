// Zoom initial conditions: nested white noise, and particles of three resolutions around a high-resolution Lagrangian region.
#pragma once
#include <cstdint>
#include <vector>

#include "core/Units.hpp"
#include "ics/CosmologicalBox.hpp"

namespace fountain::ics {

// The grid levels of a zoom (N = 2^level cells per side): raw white noise on `coarsest`, each
// finer level refined from it; particles of the `finest` level (dark matter and gas) in the
// high-resolution region, of the `parent` level around it, of the coarsest level elsewhere.
// coarsest is parent or parent - 1; finest >= parent.
struct ZoomLevels {
  int coarsest = 5, parent = 6, finest = 7;
};

// White noise on `finest`'s grid (cell (i N + j) N + k) refined level by level from raw noise
// on `coarsest` (COSMOLOGY.md C8.3): a child cell's value is its raw noise g_c less the mean of
// its 8 siblings' plus w_parent / sqrt(8). The mean of every block of 8 children is then its
// parent's value / sqrt(8), so the coarse levels' noise is kept, and the children are again
// unit-variance white noise. The same for any thread count.
std::vector<double> nested_noise(std::uint64_t seed, int coarsest, int finest);

// The cells of `level`'s grid within `cells` cells of a marked one (periodic, in every
// direction: a cube of side 2 cells + 1 about each).
std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& marked, int level, int cells);

// A zoom's particles from the box's parameters (p.level is ignored: the levels give the grids)
// and the high-resolution region as marked cells of the parent level. The region's cells hold
// 8^(finest - parent) dark matter particles (Species::DarkMatter) and as many gas particles
// (when p.gas) each; the parent-level cells within 2 of the region, and every parent-level
// cell of a coarsest-level cell that holds any of those, one low-resolution particle each;
// every other coarsest-level cell one (with coarsest = parent, every other parent-level cell). A low-resolution particle (Species::LowResDarkMatter)
// has its block's matter, at the mean of its fine cells' positions and velocities. IDs: fine
// dark matter 1 + n (n the finest-level cell), gas 1 + n + 2^40, parent-level particles
// 1 + n + 2^41, coarsest-level ones 1 + n + 2^42. With no region marked, every parent-level
// cell is one dark matter particle (Species::DarkMatter, ID 1 + n): the parent run's initial
// conditions, the zoom's low-resolution particles exactly.
CosmologicalBox make_zoom(const CosmologicalBoxParams& p, const ZoomLevels& levels, const std::vector<std::uint8_t>& region,
                          const Units& units);

}  // namespace fountain::ics
