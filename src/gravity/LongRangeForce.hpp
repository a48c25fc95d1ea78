// A periodic run's long-range gravity: the mesh, and how many cells a run's mesh has.
#pragma once
#include <cmath>
#include <cstddef>
#include <memory>

#include "gravity/PeriodicMesh.hpp"

namespace fountain::gravity {

// The mesh's forces go straight into the particles' a_mesh and potential_mesh
// (compute_long_range).
struct LongRangeForce {
  PeriodicMesh mesh;

  // slabs: the ranks that share the mesh (null: this process holds all of it).
  LongRangeForce(int cells, double box, double r_s, double G, std::unique_ptr<MeshSlabs> slabs = nullptr)
      : mesh(cells, box, r_s, G, std::move(slabs)) {}

  // The mesh a run of `particles` in a box of side `box` uses: `cells` when set, otherwise
  // the smallest power of two at least the particles per side (and at least 16, so that the
  // short-range cut-off stays below half the box).
  static int choose_cells(int cells, std::size_t particles) {
    if (cells > 0) return cells;
    const double per_side = std::cbrt(static_cast<double>(particles));
    int n = 16;
    while (n < per_side - 1e-9 && n < 4096) n *= 2;
    return n;
  }
};

}  // namespace fountain::gravity
