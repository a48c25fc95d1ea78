// Octree of source particles with quadrupole moments, and the gather-only walk that gives a target's acceleration.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/ForEach.hpp"
#include "core/Vec3.hpp"
#include "gravity/GravityKernel.hpp"
#include "gravity/GravityMultipole.hpp"
#include "gravity/GravityTypes.hpp"

namespace fountain::gravity {

struct TreeConfig {
  int max_leaf_size = 8;  // a node with more particles than this is split (unless too deep)

  // Periodic boundaries (TreePM, as in GADGET-2): the tree gives only the short-range force,
  // cut off at a few r_s, far below half the box, so the walk takes the nearest image of each
  // node and particle (offsets wrapped into [-box/2, box/2)); the long range, periodic images
  // included, comes from PeriodicMesh. Walks on a periodic tree need WalkConfig::split.
  bool periodic = false;
  double box_size = 0.0;
  // How a refit fits a cube whose content has left it: false grows it about its built centre;
  // true takes the cube about the content, so a node carried by a bulk flow keeps its size
  // (the engine's periodic runs, where flows carry whole regions between rebuilds; the
  // isolated runs keep the first rule, with which their results were validated).
  bool fit_cubes = false;
};

// The relative opening criterion for a node of mass M and side l whose centre of mass is at
// distance r, for a target with previous acceleration |a_old| (G included). Each form bounds
// by alpha_force |a_old| the leading neglected term of one expansion order (docs/gravity.md):
enum class OpeningCriterion {
  // GADGET-2 (forcetree.c): accept when G M l^2 / r^4 <= alpha |a_old|. That is the size of
  // the quadrupole term, the first one a monopole-only expansion leaves out; with the
  // quadrupole included it bounds a term the walk does compute.
  gadget2_monopole,
  // GADGET-4 (gwalk.cc, MULTIPOLE_ORDER = 3): accept when G M l^3 / r^5 <= alpha |a_old|, the
  // size of the octupole term, the first one a monopole + quadrupole expansion leaves out.
  relative_quadrupole,
};

struct WalkConfig {
  double G = 1.0;             // in internal units
  double alpha_force = 0.01;  // relative criterion: accept when (see `criterion`) <= alpha |a_old|
  double theta = 0.5;         // Barnes-Hut angle, used while a target has no |a_old|
  OpeningCriterion criterion = OpeningCriterion::gadget2_monopole;  // the paper's (GADGET)
  MultipoleOrder expansion = MultipoleOrder::quadrupole;  // terms used for an accepted node
  // Whether a node within some target's softening may be accepted (by the same criterion) and
  // evaluated with the softened expansion (softened_node_field); otherwise it is opened down
  // to its particles. Needs the quadrupole expansion.
  bool softened_nodes = true;
  GravitySplit split{};
};

// One node. The traceless quadrupole is Q = sum m (3 s s^T - |s|^2 I) with s = x - com, stored
// as xx, yy, zz, xy, xz, yz. The fields the walk reads come first, together (96 bytes).
struct TreeNode {
  Vec3 centre;  // geometric centre of the cube
  double side = 0.0;
  Vec3 built_centre;  // the centre when built; a refit keeps it while the built cube holds the node
  Vec3 content_lo, content_hi;  // the box around the node's particles (empty: lo > hi)
  Vec3 com;
  double mass = 0.0;
  double max_softening = 0.0;  // largest Plummer-equivalent eps of the particles inside
  double min_softening = 0.0;  // smallest
  std::int32_t first = 0;      // the node's particles are [first, first + count) in tree order
  std::int32_t count = 0;
  // -1 for a leaf; otherwise the next node in the array. kPruned: another rank's node whose
  // children and particles that rank did not send (TreeAcrossRanks), as no walk here opens it.
  std::int32_t first_child = -1;
  static constexpr std::int32_t kPruned = -2;
  std::int32_t next = -1;         // node to visit after this one's subtree; -1 ends the walk
  std::array<double, 6> quadrupole{};
  double second_moment = 0.0;  // sum m |x - com|^2: the trace the softened expansion needs
  double built_side = 0.0;  // the cube's side when built; a refit grows `side` from it
};

// Built from the sources (copied, in tree order) and refitted to their later positions; in
// between, read-only: any number of walks may run on it at once from any threads, and each
// walk's result depends only on the tree and its targets, so per-cell walk tasks are
// reproducible whatever the thread count.
class GravityTree {
 public:
  GravityTree(std::span<const Vec3> positions, std::span<const double> masses,
              std::span<const double> softenings, const TreeConfig& config = TreeConfig{});

  // Keeps the topology and the particles' tree order, and recomputes every node from the
  // sources' new positions, masses and softenings (same count, same source indices): moments,
  // and cubes that hold their particles again, so every opening test stays as valid as after a
  // build: the built cube while it still holds them, otherwise that cube grown about its
  // centre or (TreeConfig::fit_cubes) the cube about their bounding box no smaller than the
  // built one.
  // O(N) and no sort, for the steps between rebuilds. Unchanged sources give the built tree
  // back, bit for bit.
  void refit(std::span<const Vec3> positions, std::span<const double> masses, std::span<const double> softenings);
  // Whether a refit has grown some node's cube past twice its built side (its particles have
  // spread): the walk then opens more than a fresh tree would, and the caller should build anew.
  bool loose() const { return loose_; }

  // The same refit in parts, so that tasks can share it out: at its build the tree deals its
  // subtrees into kRefitGroups groups of about equal particle count. refit_group(g, fetch)
  // for every g (in any order, at once from different threads), then finish_refit() for the
  // nodes above them; the result is refit()'s, bit for bit. fetch(i) gives source i as a
  // RefitSource; a source that is not finite, or has a negative mass or softening, throws.
  static constexpr int kRefitGroups = 8;
  struct RefitSource {
    Vec3 x;
    double mass;
    double softening;
  };
  template <class Fetch>
  void refit_group(int g, const Fetch& fetch) {
    check_refittable();
    bool loose = false;
    for (std::int32_t p = group_start_[static_cast<std::size_t>(g)]; p < group_start_[static_cast<std::size_t>(g) + 1]; ++p) {
      const std::int32_t root = pieces_[static_cast<std::size_t>(p)];
      const TreeNode& node = nodes_[static_cast<std::size_t>(root)];
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const std::int32_t i = index_[static_cast<std::size_t>(k)];
        store_source(k, i, fetch(static_cast<std::size_t>(i)));
      }
      loose = piece_moments(root) || loose;
    }
    group_loose_[static_cast<std::size_t>(g)] = loose;
  }
  void finish_refit();
  // Particles in refit group g.
  std::int64_t refit_group_count(int g) const;

  GravityResult accelerate(const GravityTarget& target, const WalkConfig& config) const;

  // The same for many targets (an engine task passes its cell's active particles): they are
  // walked in spatially compact groups of up to group_size(config), each group sharing one
  // walk whose opening tests hold for every point of the group's box. A target's answer
  // therefore depends on the targets passed with it (never on the thread running the call,
  // nor on whether `for_each` runs the groups in parallel).
  // TreePM walks take groups of 64 (32 and 128 measured slower): their lists are cut per
  // target to the pairs within the cut-off, so a wider group costs less than a second walk;
  // isolated walks evaluate whole lists for every target and keep to 16.
  static constexpr int kGroupSize = 64;  // the largest group, a TreePM walk's
  static constexpr int kIsolatedGroupSize = 16;
  static int group_size(const WalkConfig& config) { return config.split.enabled() ? kGroupSize : kIsolatedGroupSize; }
  void accelerate(std::span<const GravityTarget> targets, const WalkConfig& config, std::span<GravityResult> results,
                  const ForEach& for_each = {}) const;

  // Room for the nodes of a tree of n sources, enough for the sets measured at 8 per leaf
  // (0.36 n nodes clustered, 0.45 n uniform, 0.57 n on the lattice of cosmological initial
  // conditions), so that a build rarely grows the array: doubling it from a short guess had
  // set memory peaks.
  static std::size_t node_estimate(std::size_t n, int max_leaf_size) {
    return 5 * n / static_cast<std::size_t>(std::max(1, max_leaf_size)) + 16;
  }

  const std::vector<TreeNode>& nodes() const { return nodes_; }
  // Source index of the particle at each tree position.
  const std::vector<std::int32_t>& order() const { return index_; }
  std::size_t size() const { return index_.size(); }
  const TreeConfig& config() const { return config_; }

 private:
  // TreeAcrossRanks.cpp builds a rank's subtrees with these and assembles its tree from them.
  friend class TreeAssembler;
  struct Cube {
    Vec3 centre;
    double side = 0.0;
  };
  // The root cube GravityTree's constructor takes for these sources (their bounding box).
  static Cube root_cube(const Vec3& lo, const Vec3& hi);
  // The subtree that a tree of more sources holds at node `cube` of depth `depth`, when these
  // are that node's sources, in the larger tree's order: the same nodes, in the same order,
  // with the same moments, bit for bit.
  GravityTree(std::span<const Vec3> positions, std::span<const double> masses, std::span<const double> softenings,
              const TreeConfig& config, const Cube& cube, int depth);
  explicit GravityTree(const TreeConfig& config) : config_(config) {}
  void build_from(std::span<const Vec3> positions, std::span<const double> masses, std::span<const double> softenings,
                  const Cube& cube, int depth);

  // Below this depth a node's side is still far above a double's resolution of any sane
  // coordinate; deeper nodes are kept as (over-full) leaves, so coincident particles end the
  // recursion instead of looping forever.
  static constexpr int kMaxDepth = 48;
  // TreePM: a node of at most this many particles that the criterion opens gives its particles
  // directly (docs/gravity.md, "Periodic TreePM").
  static constexpr std::int32_t kDirectNodeSize = 32;
  static int octant(const Vec3& x, const Vec3& centre) {
    return (x.x >= centre.x ? 1 : 0) | (x.y >= centre.y ? 2 : 0) | (x.z >= centre.z ? 4 : 0);
  }
  static Vec3 child_centre(const Vec3& centre, double side, int o) {
    return {centre.x + ((o & 1) ? 0.25 : -0.25) * side, centre.y + ((o & 2) ? 0.25 : -0.25) * side,
            centre.z + ((o & 4) ? 0.25 : -0.25) * side};
  }

  struct SortItem {
    Vec3 x;
    std::int32_t index;
  };
  void build(std::int32_t first, std::int32_t count, const Vec3& centre, double side, int depth,
             std::vector<SortItem>& items, std::vector<SortItem>& scratch);
  void load_sources(std::span<const Vec3> positions, std::span<const double> masses,
                    std::span<const double> softenings);
  // Source i (of the caller's numbering) into tree position k, checked.
  void store_source(std::int32_t k, std::int32_t i, const RefitSource& s);
  void compute_moments();
  // The moments and cube of one node from its particles or its children's; true if the
  // cube has grown past twice its built side.
  bool node_moments(std::int32_t n);
  // The refit parts: subtrees whose roots are pieces_ (in preorder), group g holding
  // pieces [group_start_[g], group_start_[g+1]); the nodes above them are top_nodes_.
  void plan_refit_groups();
  // Moments of every node of the subtree rooted at `root`; true if one grew loose.
  bool piece_moments(std::int32_t root);

  struct Group;
  struct InteractionList;
  // What a walk does at a node (decide): passes it by (beyond the TreePM cut-off), takes its
  // expansion, goes into its children, or lists its particles. `pruned`: it would go in, but
  // the node's inside is not here.
  enum class Visit { skip, accept, accept_softened, open, list, pruned };
  struct WalkRules {
    double theta2 = 0.0, cutoff = 0.0, slack = 0.0;
    bool split = false, soft_allowed = false;
  };
  // The node's offsets from the group's centre, its gap to the group's box and the pair
  // spline length, as decide() found them (the listing of particles reuses them).
  struct NodeOffsets {
    double ox = 0.0, oy = 0.0, oz = 0.0, d2box = 0.0, h = 0.0;
  };
  static WalkRules walk_rules(const WalkConfig& config, const TreeNode& root);
  Visit decide(const TreeNode& node, const Group& g, const WalkConfig& config, const WalkRules& rules,
               NodeOffsets& o) const;
  void walk_group(const Group& g, const WalkConfig& config, InteractionList& list) const;
  void evaluate_group(Group& g, const WalkConfig& config, const InteractionList& list) const;
  // The same lists with the TreePM short-range factors (GravityWalkShortRange.cpp).
  void evaluate_group_short_range(Group& g, const WalkConfig& config, const InteractionList& list) const;
  // The nearest image of an offset along one axis (the offset itself for open boundaries).
  // Most offsets in a walk are already within half a box: those skip the rounding (a libm call
  // on plain x86-64), with the same result.
  double image(double offset) const {
    if (!config_.periodic || std::fabs(offset) <= 0.5 * config_.box_size) return offset;
    return offset - config_.box_size * std::nearbyint(offset / config_.box_size);
  }

  TreeConfig config_;
  std::vector<TreeNode> nodes_;
  std::vector<std::int32_t> index_;  // tree order -> source index
  std::vector<Vec3> pos_;            // sources in tree order
  std::vector<double> mass_;
  std::vector<double> spline_;     // the sources' spline lengths (2.8 eps)
  // The walk's float loops measure lengths in this unit: a power of two near the root's side
  // at build, so that scaling by it is exact and float's exponent range covers the
  // separations whatever the internal unit of length (cm would underflow 1/r^3 in float).
  double length_unit_ = 1.0;
  std::vector<float> spline_f_;      // spline_ in float and in length_unit_, for the near loop
  std::vector<float> spline_inv_f_;  // 1 / spline_f_
  std::vector<double> eps_;          // the sources' softenings
  std::vector<std::int32_t> pieces_, top_nodes_;
  std::array<std::int32_t, kRefitGroups + 1> group_start_{};
  std::array<bool, kRefitGroups> group_loose_{};
  bool loose_ = false;
  bool across_ranks_ = false;  // assembled from several ranks' parts: rebuilt, never refitted
  void check_refittable() const;
};

}  // namespace fountain::gravity
