// A gravity tree over sources that several ranks hold, assembled on each rank so that its walks give one rank's tree's results bit for bit.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "core/Collectives.hpp"
#include "core/Vec3.hpp"
#include "gravity/GravityTree.hpp"

namespace fountain::gravity {

// What assembling the tree needs of the ranks (core/Collectives.hpp).
using TreeMessages = Collectives;

// One rank's sources: its share of the run's sources, in the run's order (the order one
// rank's tree takes its sources in: within a leaf, and so in every sum, sources follow it).
// `place` is the source's index in that order; a rank's places increase along its sources.
// The sources are read where the run keeps them (a copy of them all would add 40 bytes a
// source to the peak of every build and refit).
struct RankSources {
  struct Source {
    Vec3 position;
    double mass = 0.0, softening = 0.0;
  };
  std::size_t count = 0;
  std::function<Source(std::size_t)> source;  // source k, k < count
  std::span<const std::uint64_t> places;
  // The index each source has in the assembled tree, as the walks' targets name it
  // (GravityTarget::source_index); empty: its position here.
  std::span<const std::int32_t> names = {};

  // Sources laid out in arrays of one length each (which must outlive the use).
  static RankSources of_arrays(std::span<const Vec3> positions, std::span<const double> masses,
                               std::span<const double> softenings, std::span<const std::uint64_t> places,
                               std::span<const std::int32_t> names = {});
};

// What bounds the walks of the targets a rank passes to one call of GravityTree::accelerate
// (a cell's active particles, say): the walk groups them among themselves only, so the box
// around them holds every group's box. Another rank sends the inside of each of its nodes
// that some walk of these targets could open. A summary, so that the targets need not be
// held for the assembly.
struct TargetBatch {
  TargetBatch(std::span<const GravityTarget> targets);  // NOLINT: a batch stands for its targets
  bool empty = true;
  Vec3 lo, hi;                             // the targets' positions' box
  double h_min = 0.0, h_max = 0.0;         // their spline lengths
  double a_min = 0.0;                      // the smallest |a_old| of those that have one
  bool any_barnes_hut = false, any_relative = false;  // with no |a_old|; with one
};

// What one assembly held and moved on this rank, for the traffic figures.
struct TreeAcrossRanksCounts {
  std::int64_t top_nodes = 0;      // nodes of the top (several ranks' sources), on every rank
  std::int64_t gathered_nodes = 0;  // of which built from every rank's sources there (small nodes)
  std::int64_t own_subtrees = 0;    // nodes below the top holding this rank's sources only
  std::int64_t nodes_sent = 0, sources_sent = 0;          // to other ranks, for their walks
  std::int64_t nodes_received = 0, sources_received = 0;  // from them
  std::int64_t bytes_sent = 0;
};

class TreeAssembler;

// The tree of every rank's sources as seen from this rank:
//   - the top: the nodes holding several ranks' sources, the same on every rank, with their
//     moments summed from their children's as one rank sums them; a small one (at most a
//     leaf's sources, or TreePM's directly listed node size) is built by every rank from every
//     rank's sources in it;
//   - this rank's nodes whole (the subtrees of its sources only, built as one rank builds them);
//   - another rank's nodes as far as this rank's target batches may open them, with the
//     moments the owner computed; what no walk of those batches opens is left out (a walk that
//     reaches into it throws a std::logic_error rather than answer differently).
// Walks of the batches' targets on tree_for()'s tree then give what one rank's GravityTree
// over every source gives them, bit for bit, after the same builds and refits. Sources of this
// rank keep their name (RankSources::names, as the targets' source_index names them); every
// other rank's source has index kForeignSource.
// Every call is a collective: every rank calls it, with the same configurations.
class TreeAcrossRanks {
 public:
  // The topology, from every rank's sources at their present positions (GravityTree's build).
  TreeAcrossRanks(TreeMessages& ranks, const RankSources& mine, const TreeConfig& tree_config,
                  const WalkConfig& walk_config);
  ~TreeAcrossRanks();
  TreeAcrossRanks(TreeAcrossRanks&&) noexcept;
  TreeAcrossRanks& operator=(TreeAcrossRanks&&) noexcept;
  // The same sources in the same order, moved or changed in mass or softening: every moment
  // anew on the kept topology (GravityTree::refit).
  void refit(TreeMessages& ranks, const RankSources& mine);
  // Whether some rank's refit grew a node's cube past twice its built side (the same answer
  // on every rank): the caller should build anew, as one rank would.
  bool loose() const;
  // The tree for walks of these batches' targets, valid until the next call (its own and
  // gathered subtrees are kept from call to call, the rest is made anew).
  const GravityTree& tree_for(TreeMessages& ranks, std::span<const TargetBatch> batches);
  // The tree the last tree_for() made.
  const GravityTree& last_tree() const;
  // What the last tree_for() held and moved (the topology's counts since the build).
  const TreeAcrossRanksCounts& counts() const;

 private:
  std::unique_ptr<TreeAssembler> impl_;
};

constexpr std::int32_t kForeignSource = -2;

}  // namespace fountain::gravity
