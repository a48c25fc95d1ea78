// Which MPI rank owns each top-level cell: the grid ordered along a Hilbert curve, cut into contiguous pieces of equal measured work.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

namespace fountain::domain {

// A top-level grid of nx x ny x nz cells, indexed (i * ny + j) * nz + k.
struct TopGrid {
  int nx = 1, ny = 1, nz = 1;
  int size() const { return nx * ny * nz; }
  int index(int i, int j, int k) const { return (i * ny + j) * nz + k; }
};

// The Hilbert key of cell (i, j, k) in a cube of 2^bits cells per side (Skilling 2004,
// "Programming the Hilbert curve"): cells whose keys differ by one share a face, so a run of
// consecutive keys is a compact region with a small surface.
std::uint64_t hilbert_key(std::uint32_t i, std::uint32_t j, std::uint32_t k, int bits);

// Every cell of the grid, in Hilbert order (of the smallest power-of-two cube holding it;
// grids that are not such cubes skip the keys outside them, so a few consecutive cells
// may then touch only at an edge).
std::vector<int> hilbert_order(const TopGrid& grid);

// The owner of each cell (indexed as the grid): the curve cut into `ranks` contiguous runs
// whose work is as equal as whole cells allow. A cell goes to the rank whose share of the
// total contains the midpoint of the cell's work on the curve, so the result depends only
// on the inputs, ranks may own no cell (more ranks than cells, or one heavy cell), and
// all-zero work is treated as equal work per cell.
std::vector<int> partition(const std::vector<int>& curve, std::span<const double> work, int ranks);

// max over ranks of its work / mean work per rank, minus one: 0 is perfect balance.
double imbalance(std::span<const double> work, std::span<const int> owner, int ranks);

// Whether a run should repartition: the measured imbalance passed the threshold (a parameter).
inline bool needs_repartition(double measured_imbalance, double threshold) { return measured_imbalance > threshold; }

}  // namespace fountain::domain
