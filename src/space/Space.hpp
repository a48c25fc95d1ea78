// The domain: a top-level grid of cells, each split into an octree, and neighbour-cell lists.
#pragma once
#include <array>
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/ForEach.hpp"
#include "core/Vec3.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "space/Cell.hpp"

namespace fountain {

struct SpaceConfig {
  bool periodic = false;
  Vec3 box_size;            // periodic box (ignored for open boundaries)
  int split_size = 256;     // octree leaves hold at most this many particles
  int top_cells = 0;        // top-level cells along the longest side; 0 = automatic
  std::string top_cells_origin = "key 'space.top_cells'";  // where it was set, for messages
  double skin = 0.25;       // leaves cover (1 + skin) h_max
  // space.rebuild_skin's 'auto'. A comoving box spends its skin on bulk motion: twice the skin
  // means fewer rebuilds at no cost in the SPH loops (docs/performance.md, "Cosmological box");
  // elsewhere 0.25 suits, and small periodic boxes keep their reach.
  static double default_skin(bool comoving) { return comoving ? 0.5 : 0.25; }
};

class Space {
 public:
  explicit Space(SpaceConfig config) : config_(config) {}

  // Sorts the particles of both species into cells (every field permuted), builds the octree,
  // the leaves' cover radii and their neighbour lists: recut, then find_neighbours. Work on
  // separate leaves (ordering their particles, their lists) and pieces of the permutation go
  // through `for_each` (serially when it is empty); the result does not depend on their order.
  void rebuild(GasParticles& gas, CollisionlessParticles& dm, const ForEach& for_each = {});
  // The first part of rebuild: cells, particle order, cover radii; positions are wrapped into
  // a periodic box. The neighbour lists are stale until find_neighbours, which reads only the
  // cells (so the caller may meanwhile work on the particles, as the engine's tree build does).
  // `gas_order`, if given, receives the permutation: gas particle i after the recut is the one
  // that was at gas_order[i] before it (its old contents become the next recut's scratch).
  void recut(GasParticles& gas, CollisionlessParticles& dm, const ForEach& for_each = {},
             std::vector<std::size_t>* gas_order = nullptr);
  void find_neighbours(const ForEach& for_each = {});

  // The recut in parts, for ranks that each hold some of the particles (recut is set_frame,
  // a sort by top cell, build_subtree for each top cell, assemble, the leaves' h_max and
  // v_max from their particles, set_covers):
  // The box (periodic: the configured one; open: the particles' bounding box lo..hi, as
  // recut widens it) and the top-level grid for n gas and n_dm collisionless particles; the
  // top cells made, empty. A caller fills in their first, count, dm_first and dm_count.
  void set_frame(const Vec3& lo, const Vec3& hi, std::size_t n, std::size_t n_dm);
  // The cells below the top cells from each top cell's subtree (build_subtree's, with its
  // leaves' h_max, v_max and ti_end_min where known), numbered as recut numbers them, and
  // the list of leaves.
  void assemble(const std::vector<std::vector<Cell>>& subtrees);
  // The cover radii from the leaves' h_max, inner nodes' h_max and covers from below, the
  // motion bounds reset; throws InputError when a periodic box is too small for them.
  void set_covers();

  // The octree below one top-level cell and its particles' order, from its particles alone,
  // as recut builds it: whoever holds a top cell's particles (in the order they had before)
  // can build its part of the cells without the others'. `top`: the top cell's box and depth
  // (as recut made it; its counts are the slices'). The slices gas_order and dm_order list the
  // top cell's particles as indices into gas_x and dm_x, in their order before the recut; they
  // come back in the recut's order (the scratch slices are as long). The cells come back
  // numbered as recut numbers a subtree, [0] being the top cell, with parents and children
  // indexing the vector and particle ranges counted from the top cell's first particle.
  // Depends on the box (recut sets it), the split size and periodicity only.
  std::vector<Cell> build_subtree(const Cell& top, const std::vector<Vec3>& gas_x, std::span<std::size_t> gas_order,
                                  std::span<std::size_t> gas_scratch, const std::vector<Vec3>& dm_x,
                                  std::span<std::size_t> dm_order, std::span<std::size_t> dm_scratch) const;
  // The lists of the leaves in slots [first, last) of leaves() only; the others are left
  // empty, for lists found elsewhere (another rank's share) to be set with set_lists.
  void find_neighbours(const ForEach& for_each, std::size_t first, std::size_t last);
  // Sets the lists of the leaf in slot `l` of leaves(), as find_neighbours would have found them.
  void set_lists(std::size_t l, std::span<const int> neighbours, std::span<const int> surroundings);

  const std::vector<Cell>& cells() const { return cells_; }
  std::vector<Cell>& cells() { return cells_; }
  Cell& cell(int c) { return cells_[static_cast<std::size_t>(c)]; }
  const Cell& cell(int c) const { return cells_[static_cast<std::size_t>(c)]; }
  const std::vector<int>& leaves() const { return leaves_; }
  // Leaves hold gas, dark matter or both; the hydro tasks skip those without gas.
  // Leaves whose gas particles may interact with those of leaf `c` (not `c` itself), in a fixed order.
  const std::vector<int>& neighbours(int c) const { return neighbours_[static_cast<std::size_t>(leaf_slot_[static_cast<std::size_t>(c)])]; }
  // Leaves with gas whose boxes lie within surroundings_reach(c) of leaf `c`'s (not `c`
  // itself): the only ones whose motion can bring a particle within its cover before any
  // particle has moved half that far (Engine::prepare_step).
  const std::vector<int>& surroundings(int c) const { return surroundings_[static_cast<std::size_t>(leaf_slot_[static_cast<std::size_t>(c)])]; }
  static double surroundings_reach(const Cell& c) { return 2.0 * c.r_cover; }
  // The separation a - b of two positions, as its nearest periodic image.
  Vec3 separation(const Vec3& a, const Vec3& b) const {
    Vec3 d = a - b;
    if (config_.periodic)
      for (int k = 0; k < 3; ++k) {
        if (d[k] > half_[k]) d[k] -= size_[k];
        else if (d[k] < -half_[k]) d[k] += size_[k];
      }
    return d;
  }

  const SpaceConfig& config() const { return config_; }
  bool periodic() const { return config_.periodic; }
  const Vec3& box_lo() const { return lo_; }
  const Vec3& box_size() const { return size_; }
  int rebuild_count() const { return rebuilds_; }
  // The top-level grid: cells 0 .. nx*ny*nz-1 are its cells, indexed (i * ny + j) * nz + k.
  const std::array<int, 3>& top_grid() const { return ntop_; }
  // The top-level cell that holds cell c.
  int top_cell_of(int c) const {
    while (cells_[static_cast<std::size_t>(c)].parent >= 0) c = cells_[static_cast<std::size_t>(c)].parent;
    return c;
  }
  // The top-level cell whose box holds position x (clamped to the grid).
  int top_cell_at(const Vec3& x) const;
  // The smallest cell whose box holds x: a leaf, or an inner cell where x lies in an empty octant.
  int cell_at(const Vec3& x) const;

  // Distance between the boxes of two cells (nearest periodic image).
  double box_distance(const Cell& a, const Cell& b) const;

 private:
  struct SortState;
  void split(int c, SortState& s) const;
  void collect_leaves(int leaf, int node, std::vector<int>& neighbours, std::vector<int>& surroundings) const;
  // The top-level grid's indices along axis k whose cells may lie within `reach` of cell a's
  // box, ascending.
  static constexpr int kMaxTopPerAxis = 128;
  // space.top_cells may ask for this many top cells whatever the particle number.
  static constexpr std::size_t kFewestTopCellsAllowed = 64;
  struct TopRange {
    std::array<int, kMaxTopPerAxis> index;
    int count = 0;
  };
  TopRange top_range(const Cell& a, double reach, int k) const;
  double wrap_delta(double d, int dim) const;

  SpaceConfig config_;
  Vec3 lo_, size_, half_;
  std::vector<Cell> cells_;
  std::vector<int> top_;
  std::array<int, 3> ntop_{1, 1, 1};
  std::vector<int> leaves_;
  std::vector<int> leaf_slot_;
  std::vector<std::vector<int>> neighbours_;
  std::vector<std::vector<int>> surroundings_;
  int rebuilds_ = 0;
  // Kept from one recut to the next: fresh buffers of this size (MBs) would be zero-filled and
  // faulted in again at every recut.
  std::vector<std::size_t> sort_order_, sort_scratch_, dm_sort_order_, dm_sort_scratch_, sort_key_;
  std::vector<std::byte> permute_scratch_;
};

}  // namespace fountain
