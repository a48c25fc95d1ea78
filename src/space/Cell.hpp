// One node of the cell tree: a box holding a contiguous range of particles.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

#include "core/Vec3.hpp"

namespace fountain {

struct Cell {
  Vec3 lo;                       // lower corner of the box
  Vec3 width;                    // box size
  std::size_t first = 0;         // gas particles [first, first + count)
  std::size_t count = 0;
  std::size_t dm_first = 0;      // dark matter particles [dm_first, dm_first + dm_count)
  std::size_t dm_count = 0;
  std::array<int, 8> children{-1, -1, -1, -1, -1, -1, -1, -1};
  int parent = -1;
  int depth = 0;
  bool leaf = true;

  // Set at rebuild: the radius around the box within which every neighbour of its
  // particles is found (leaf), or the largest such radius below this node (inner node).
  double r_cover = 0.0;

  // Updated as the run goes (leaves only).
  double h_max = 0.0;            // largest h of its particles, after the last drift or ghost
  double v_max = 0.0;            // largest |v_full|, after the last kick
  double dx_max = 0.0;           // bound on how far a particle moved since the rebuild
  // Bound on how far a particle of any other leaf that could come within reach moved since
  // the rebuild (Engine::prepare_step): the cover must outlast h growth, dx_max and this.
  double dx_around = 0.0;
  std::int64_t ti_drift = 0;     // integer time its particles were drifted to
  std::int64_t ti_end_min = 0;   // earliest end of a particle's step in the cell (any species)

  // Energy radiated by its particles' kicks this step (gathered by the engine after each step).
  double radiated = 0.0;

  Vec3 centre() const { return lo + width * 0.5; }
};

}  // namespace fountain
