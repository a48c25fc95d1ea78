#include "gravity/TreeAcrossRanks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/ByteMessages.hpp"
#include "gravity/GravityWalkGroup.hpp"

namespace fountain::gravity {

namespace {

struct SourceRecord {
  Vec3 x;
  double mass = 0.0, softening = 0.0;
  std::uint64_t place = 0;
};

// What bounds the walks of one rank's target batches (several batches merged): their box,
// the spline lengths, and which opening criteria its groups may use, with the smallest
// |a_old| of those that use the relative one.
struct Envelope {
  Vec3 lo, hi;
  double h_max = 0.0, h_min = std::numeric_limits<double>::infinity();
  double a_min = std::numeric_limits<double>::infinity();
  std::int32_t any_barnes_hut = 0, any_relative = 0;
};

void widen(Envelope& e, const Envelope& other) {
  for (int d = 0; d < 3; ++d) {
    e.lo[d] = std::min(e.lo[d], other.lo[d]);
    e.hi[d] = std::max(e.hi[d], other.hi[d]);
  }
  e.h_max = std::max(e.h_max, other.h_max);
  e.h_min = std::min(e.h_min, other.h_min);
  e.a_min = std::min(e.a_min, other.a_min);
  e.any_barnes_hut |= other.any_barnes_hut;
  e.any_relative |= other.any_relative;
}

double extent(const Envelope& e) { return std::max({e.hi.x - e.lo.x, e.hi.y - e.lo.y, e.hi.z - e.lo.z}); }

// Frees a vector's memory (`v = {}` would pick the initializer-list assignment, which keeps
// its capacity).
template <class T>
void release(std::vector<T>& v) {
  std::vector<T>().swap(v);
}

}  // namespace

// The assembly's steps, each a collective (docs/gravity.md, "Across ranks").
class TreeAssembler {
 public:
  TreeAssembler(TreeMessages& ranks, const RankSources& mine, const TreeConfig& tree_config,
                const WalkConfig& walk_config)
      : tree_config_(tree_config), walk_config_(walk_config), tree_(tree_config) {
    check(mine);
    ranks_ = &ranks;
    mine_ = mine;
    gather_limit_ = std::max<std::int64_t>(tree_config.max_leaf_size,
                                           walk_config.split.enabled() ? GravityTree::kDirectNodeSize : 0);
    tree_.across_ranks_ = true;
    has_sources_ = find_cube();
    if (!has_sources_) return;
    tree_.length_unit_ = std::ldexp(1.0, std::ilogb(cube_.side));
    build_top();
    order_ = preorder();
    release(scratch_);
    // Room for the kept part at once (GravityTree's estimate of its nodes), rather than by
    // doubling, which set the peak of a rank's memory here.
    std::size_t kept = 0;
    for (const TopNode& node : top_)
      if (node.kind == Kind::gathered) kept += static_cast<std::size_t>(node.total);
    kept += mine_.count;
    kept_sources_ = kept;
    tree_.nodes_.reserve(GravityTree::node_estimate(kept, tree_config_.max_leaf_size));
    tree_.index_.reserve(kept);
    for (auto* v : {&tree_.mass_, &tree_.spline_, &tree_.eps_}) v->reserve(kept);
    tree_.pos_.reserve(kept);
    tree_.spline_f_.reserve(kept);
    tree_.spline_inv_f_.reserve(kept);
    // The walks start at node 0: the root's place, unless the root is a block built here.
    const TopNode& root = top_[0];
    if (root.kind == Kind::internal || (root.kind == Kind::held && root.owner != ranks_->rank()))
      tree_.nodes_.emplace_back();
    build_own_subtrees();
    gather_small_nodes(true);
    keep_gathered_members();
    prefix_nodes_ = tree_.nodes_.size();
    prefix_sources_ = tree_.pos_.size();
  }

  void refit(TreeMessages& ranks, const RankSources& mine) {
    check(mine);
    if (mine.count != own_count_)
      throw std::invalid_argument("TreeAcrossRanks::refit: " + std::to_string(mine.count) +
                                  " sources for a tree of " + std::to_string(own_count_));
    ranks_ = &ranks;
    mine_ = mine;
    if (!has_sources_) return;
    bool loose = false;
    for (const Block& block : own_blocks_) {
      for (std::int32_t k = 0; k < block.sources; ++k) {
        const std::int32_t at = block.first + k;
        const SourceRecord r = record(block.source_of[static_cast<std::size_t>(k)]);
        tree_.store_source(at, tree_.index_[static_cast<std::size_t>(at)], {r.x, r.mass, r.softening});
      }
      loose = block_moments(block) || loose;
    }
    loose_ = loose;
    gather_small_nodes(false);
  }

  bool loose() const { return loose_; }
  const TreeAcrossRanksCounts& counts() const { return counts_; }
  const GravityTree& last_tree() const { return tree_; }

  const GravityTree& tree_for(TreeMessages& ranks, std::span<const TargetBatch> batches) {
    ranks_ = &ranks;
    batches_ = batches;
    if (!has_sources_) return tree_;
    counts_.nodes_sent = counts_.sources_sent = counts_.nodes_received = counts_.sources_received = 0;
    counts_.bytes_sent = counts_.top_nodes = 0;
    exchange_essential_parts();
    assemble();
    return tree_;
  }

 private:
  enum class Kind { internal, held, gathered, empty };
  struct TopNode {
    GravityTree::Cube cube;
    int depth = 0;
    std::int64_t total = 0;
    Kind kind = Kind::internal;
    int owner = -1;                   // held: the rank whose sources alone it holds
    std::int32_t first = 0, count = 0;  // this rank's sources in it: items_[first, first + count)
    std::array<std::int32_t, 8> child{-1, -1, -1, -1, -1, -1, -1, -1};
    std::int32_t part = -1;  // held by this rank: own_blocks_[part]; gathered: gathered_blocks_[part]
  };
  struct Exported {
    TreeNode node;
    std::int32_t subtree = 1;  // exported nodes in its subtree, itself included
  };
  // A subtree built here (this rank's own, or a gathered node), kept in the tree's first
  // nodes and sources from one build to the next: its nodes [root, root + nodes), its sources
  // [first, first + sources). `exits`: its nodes whose `next` leaves it (its right edge), set
  // to wherever the top's preorder goes after it at each assembly. `source_of`: for each of its
  // sources in tree order, this rank's index of it (own) or its rank in the run's order among
  // the node's sources (gathered), for the refits.
  struct Block {
    std::int32_t root = 0, nodes = 0, first = 0, sources = 0;
    std::vector<std::int32_t> exits, source_of;
  };

  static void check(const RankSources& mine) {
    const std::size_t n = mine.count;
    if (mine.places.size() != n || (!mine.names.empty() && mine.names.size() != n))
      throw std::invalid_argument("TreeAcrossRanks: the sources, their places and their names differ in number");
    if (n > 0 && !mine.source) throw std::invalid_argument("TreeAcrossRanks: sources without a way to read them");
    for (std::size_t i = 1; i < n; ++i)
      if (!(mine.places[i - 1] < mine.places[i]))
        throw std::invalid_argument("TreeAcrossRanks: source " + std::to_string(i) +
                                    "'s place does not follow the one before it");
  }

  // The root cube, from every rank's bounds (min and max are exact in any order). False if
  // no rank has a source.
  bool find_cube() {
    Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
    Vec3 hi = -1.0 * lo;
    for (std::size_t k = 0; k < mine_.count; ++k) {
      const Vec3 x = mine_.source(k).position;
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], x[d]);
        hi[d] = std::max(hi[d], x[d]);
      }
    }
    own_count_ = mine_.count;
    std::vector<char> message;
    MessageWriter w(message);
    w.put(lo);
    w.put(hi);
    w.put(static_cast<std::int64_t>(mine_.count));
    std::int64_t total = 0;
    for (const auto& m : ranks_->allgather(message)) {
      MessageReader in(m);
      const Vec3 l = in.get<Vec3>(), h = in.get<Vec3>();
      const auto count = in.get<std::int64_t>();
      if (count == 0) continue;
      total += count;
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], l[d]);
        hi[d] = std::max(hi[d], h[d]);
      }
    }
    if (total == 0) return false;
    cube_ = GravityTree::root_cube(lo, hi);
    return true;
  }

  // The top, level by level: each rank counts its sources in the children of the level's
  // split nodes, and the sums decide every child alike on every rank: one rank's sources
  // only (held by it), few enough to gather, or split again.
  void build_top() {
    const auto n = static_cast<std::int32_t>(mine_.count);
    items_.resize(static_cast<std::size_t>(n));
    scratch_.resize(static_cast<std::size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) items_[static_cast<std::size_t>(i)] = {mine_.source(static_cast<std::size_t>(i)).position, i};
    top_.push_back(TopNode{cube_, 0, 0, Kind::internal, -1, 0, n, {}, -1});
    top_[0].child.fill(-1);
    std::vector<std::int32_t> level{0};
    while (!level.empty()) {
      // Per node: this rank's count, whether it has any, and its rank + 1 if so.
      std::vector<char> message;
      MessageWriter w(message);
      for (const std::int32_t t : level) {
        const std::int64_t c = top_[static_cast<std::size_t>(t)].count;
        w.put(c);
        w.put(static_cast<std::int64_t>(c > 0 ? 1 : 0));
        w.put(static_cast<std::int64_t>(c > 0 ? ranks_->rank() + 1 : 0));
      }
      std::vector<std::int64_t> sums(3 * level.size(), 0);
      for (const auto& m : ranks_->allgather(message)) {
        MessageReader in(m);
        for (auto& s : sums) s += in.get<std::int64_t>();
      }
      std::vector<std::int32_t> next;
      for (std::size_t k = 0; k < level.size(); ++k) {
        TopNode& node = top_[static_cast<std::size_t>(level[k])];
        node.total = sums[3 * k];
        const std::int64_t holders = sums[3 * k + 1];
        if (node.total == 0) {
          node.kind = Kind::empty;
        } else if (holders == 1) {
          node.kind = Kind::held;
          node.owner = static_cast<int>(sums[3 * k + 2] - 1);
        } else if (node.total <= gather_limit_ || node.depth >= GravityTree::kMaxDepth) {
          node.kind = Kind::gathered;
        } else {
          split(level[k], next);
        }
      }
      level = std::move(next);
    }
    for (TopNode& node : top_)
      for (auto& c : node.child)
        if (c >= 0 && top_[static_cast<std::size_t>(c)].kind == Kind::empty) c = -1;
  }

  // The top's nodes in preorder (children in octant order), as the walks visit them.
  std::vector<std::int32_t> preorder() const {
    std::vector<std::int32_t> out, stack{0};
    while (!stack.empty()) {
      const std::int32_t t = stack.back();
      stack.pop_back();
      out.push_back(t);
      const auto& child = top_[static_cast<std::size_t>(t)].child;
      for (auto c = child.rbegin(); c != child.rend(); ++c)
        if (*c >= 0) stack.push_back(*c);
    }
    return out;
  }

  // GravityTree::build's stable partition of this rank's sources in the node.
  void split(std::int32_t t, std::vector<std::int32_t>& next) {
    const TopNode node = top_[static_cast<std::size_t>(t)];
    std::array<std::int32_t, 9> start{};
    for (std::int32_t k = node.first; k < node.first + node.count; ++k)
      ++start[static_cast<std::size_t>(GravityTree::octant(items_[static_cast<std::size_t>(k)].x, node.cube.centre)) + 1];
    for (int o = 0; o < 8; ++o) start[o + 1] += start[o];
    std::array<std::int32_t, 8> fill{};
    for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
      const int o = GravityTree::octant(items_[static_cast<std::size_t>(k)].x, node.cube.centre);
      scratch_[static_cast<std::size_t>(node.first + start[o] + fill[o]++)] = items_[static_cast<std::size_t>(k)];
    }
    std::copy(scratch_.begin() + node.first, scratch_.begin() + node.first + node.count, items_.begin() + node.first);
    for (int o = 0; o < 8; ++o) {
      TopNode child;
      child.cube = {GravityTree::child_centre(node.cube.centre, node.cube.side, o), 0.5 * node.cube.side};
      child.depth = node.depth + 1;
      child.first = node.first + start[o];
      child.count = start[o + 1] - start[o];
      child.child.fill(-1);
      const auto c = static_cast<std::int32_t>(top_.size());
      top_[static_cast<std::size_t>(t)].child[static_cast<std::size_t>(o)] = c;
      top_.push_back(child);
      next.push_back(c);
    }
  }

  // The subtree of these sources (in the run's order) at top node `node`, built as one rank
  // builds it, appended to the tree's kept part. `names[j]`: the index source j takes in the
  // tree; `keys[j]`: what its block remembers of it (Block::source_of).
  struct BlockSources {
    std::vector<Vec3> x;
    std::vector<double> m, eps;
    std::vector<std::int32_t> names, keys;
    void add(const Vec3& position, double mass, double softening, std::int32_t name, std::int32_t key) {
      x.push_back(position);
      m.push_back(mass);
      eps.push_back(softening);
      names.push_back(name);
      keys.push_back(key);
    }
  };
  Block place_block(const TopNode& node, BlockSources&& in) {
    const std::vector<std::int32_t> names = std::move(in.names), keys = std::move(in.keys);
    const GravityTree sub(in.x, in.m, in.eps, tree_config_, node.cube, node.depth);
    in = {};  // the subtree has its copy
    Block block;
    block.root = static_cast<std::int32_t>(tree_.nodes_.size());
    block.nodes = static_cast<std::int32_t>(sub.nodes_.size());
    block.first = static_cast<std::int32_t>(tree_.pos_.size());
    block.sources = static_cast<std::int32_t>(sub.pos_.size());
    reserve_kept_nodes(sub.nodes_.size(), sub.pos_.size());
    for (std::size_t n = 0; n < sub.nodes_.size(); ++n) {
      TreeNode copy = sub.nodes_[n];
      copy.first += block.first;
      if (copy.first_child >= 0) copy.first_child += block.root;
      if (copy.next < 0) {
        block.exits.push_back(block.root + static_cast<std::int32_t>(n));
      } else {
        copy.next += block.root;
      }
      tree_.nodes_.push_back(copy);
    }
    for (std::size_t k = 0; k < sub.pos_.size(); ++k) {
      const auto j = static_cast<std::size_t>(sub.index_[k]);
      tree_.index_.push_back(names[j]);
      block.source_of.push_back(keys[j]);
    }
    grow_sources(tree_.pos_.size() + sub.pos_.size());
    for (std::size_t k = 0; k < sub.pos_.size(); ++k) {
      const auto at = static_cast<std::size_t>(block.first) + k;
      tree_.store_source(static_cast<std::int32_t>(at), tree_.index_[at], {sub.pos_[k], sub.mass_[k], sub.eps_[k]});
    }
    return block;
  }

  // Room for a block of `nodes` nodes over `sources` sources in the kept part. Where the first
  // guess falls short (a lattice of initial conditions has more nodes per source than a
  // clustered set), the room grows once to what the blocks so far give for every kept source,
  // with an eighth to spare, rather than by doubling.
  void reserve_kept_nodes(std::size_t nodes, std::size_t sources) {
    const std::size_t need = tree_.nodes_.size() + nodes;
    if (tree_.nodes_.capacity() >= need) return;
    const std::size_t placed = tree_.pos_.size() + sources;
    const std::size_t left = kept_sources_ > placed ? kept_sources_ - placed : 0;
    const double per_source = static_cast<double>(need) / static_cast<double>(std::max<std::size_t>(placed, 1));
    const auto more = static_cast<std::size_t>(per_source * static_cast<double>(left));
    tree_.nodes_.reserve(need + more + (need + more) / 8);
  }

  void grow_sources(std::size_t n) {
    tree_.pos_.resize(n);
    tree_.mass_.resize(n);
    tree_.spline_.resize(n);
    tree_.spline_f_.resize(n);
    tree_.spline_inv_f_.resize(n);
    tree_.eps_.resize(n);
  }

  // A block's moments from its sources, from the leaves up (GravityTree's refit); true if
  // some cube grew past twice its built side.
  bool block_moments(const Block& block) {
    bool loose = false;
    for (std::int32_t n = block.root + block.nodes - 1; n >= block.root; --n) loose = tree_.node_moments(n) || loose;
    return loose;
  }

  std::int32_t name(std::int32_t i) const { return mine_.names.empty() ? i : mine_.names[static_cast<std::size_t>(i)]; }

  // This rank's k-th source in the top's order: items_ while the top is built, then (for the
  // gathered nodes' refits) the compact list that replaces it.
  std::int32_t member(std::int32_t k) const {
    return items_.empty() ? gathered_members_[static_cast<std::size_t>(k)] : items_[static_cast<std::size_t>(k)].index;
  }

  // Once built, only the gathered nodes need this rank's sources by the top's order: their
  // list replaces the sort's arrays (32 B a source each).
  void keep_gathered_members() {
    for (TopNode& node : top_) {
      if (node.kind != Kind::gathered) continue;
      const auto first = static_cast<std::int32_t>(gathered_members_.size());
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) gathered_members_.push_back(member(k));
      node.first = first;
    }
    release(items_);
    release(scratch_);
  }

  SourceRecord record(std::int32_t i) const {
    const auto u = static_cast<std::size_t>(i);
    const RankSources::Source s = mine_.source(u);
    return {s.position, s.mass, s.softening, mine_.places[u]};
  }

  void build_own_subtrees() {
    for (TopNode& node : top_) {
      if (node.kind != Kind::held || node.owner != ranks_->rank()) continue;
      BlockSources in;
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const std::int32_t i = items_[static_cast<std::size_t>(k)].index;
        const auto u = static_cast<std::size_t>(i);
        const RankSources::Source s = mine_.source(u);
        in.add(s.position, s.mass, s.softening, name(i), i);
      }
      node.part = static_cast<std::int32_t>(own_blocks_.size());
      own_blocks_.push_back(place_block(node, std::move(in)));
      counts_.own_subtrees += own_blocks_.back().nodes;
    }
  }

  // Every rank's sources in each small node of several ranks go to every rank, which builds
  // the node's subtree from them in the run's order (or refits it: same sources, same
  // order). The message starts with whether this rank's subtrees grew loose.
  void gather_small_nodes(bool build) {
    std::vector<char> message;
    MessageWriter w(message);
    w.put(static_cast<std::int64_t>(loose_ ? 1 : 0));
    for (const TopNode& node : top_) {
      if (node.kind != Kind::gathered) continue;
      w.put(static_cast<std::int64_t>(node.count));
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) w.put(record(member(k)));
    }
    const auto all = ranks_->allgather(message);
    std::vector<MessageReader> in;
    for (const auto& m : all) {
      in.emplace_back(m);
      loose_ = (in.back().get<std::int64_t>() != 0) || loose_;
    }
    for (TopNode& node : top_) {
      if (node.kind != Kind::gathered) continue;
      struct Arrival {
        SourceRecord source;
        std::int32_t index;
      };
      std::vector<Arrival> arrivals;
      for (int r = 0; r < static_cast<int>(in.size()); ++r) {
        const auto count = in[static_cast<std::size_t>(r)].get<std::int64_t>();
        for (std::int64_t k = 0; k < count; ++k) {
          const auto s = in[static_cast<std::size_t>(r)].get<SourceRecord>();
          arrivals.push_back({s, kForeignSource});
        }
        if (r == ranks_->rank())  // this rank's own keep their index
          for (std::int32_t k = 0; k < node.count; ++k)
            arrivals[arrivals.size() - static_cast<std::size_t>(node.count) + static_cast<std::size_t>(k)].index =
                name(member(node.first + k));
      }
      std::sort(arrivals.begin(), arrivals.end(),
                [](const Arrival& a, const Arrival& b) { return a.source.place < b.source.place; });
      if (static_cast<std::int64_t>(arrivals.size()) != node.total)
        throw std::logic_error("TreeAcrossRanks: the ranks disagree on a node's sources");
      if (!build) {
        const Block& block = gathered_blocks_[static_cast<std::size_t>(node.part)];
        for (std::int32_t k = 0; k < block.sources; ++k) {
          const std::int32_t at = block.first + k;
          const SourceRecord& a = arrivals[static_cast<std::size_t>(block.source_of[static_cast<std::size_t>(k)])].source;
          tree_.store_source(at, tree_.index_[static_cast<std::size_t>(at)], {a.x, a.mass, a.softening});
        }
        loose_ = block_moments(block) || loose_;
        continue;
      }
      BlockSources in;
      for (std::size_t k = 0; k < arrivals.size(); ++k) {
        const SourceRecord& a = arrivals[k].source;
        in.add(a.x, a.mass, a.softening, arrivals[k].index, static_cast<std::int32_t>(k));
      }
      node.part = static_cast<std::int32_t>(gathered_blocks_.size());
      gathered_blocks_.push_back(place_block(node, std::move(in)));
      ++counts_.gathered_nodes;
    }
  }

  // This rank's batches as envelopes: consecutive batches merged while the box stays small
  // (a periodic walk takes nearest images from a box's centre, valid only for a box of at
  // most the width a walk group may have).
  std::vector<Envelope> envelopes() const {
    double widest = cube_.side / 8.0;
    if (tree_config_.periodic && walk_config_.split.enabled())
      widest = std::min(widest, 0.5 * tree_config_.box_size - walk_config_.split.cutoff_radius());
    std::vector<Envelope> out;
    for (const TargetBatch& batch : batches_) {
      if (batch.empty) continue;
      Envelope e;
      e.lo = batch.lo;
      e.hi = batch.hi;
      e.h_max = batch.h_max;
      e.h_min = batch.h_min;
      e.a_min = batch.a_min;
      e.any_relative = batch.any_relative ? 1 : 0;
      e.any_barnes_hut = batch.any_barnes_hut ? 1 : 0;
      if (!out.empty()) {
        Envelope merged = out.back();
        widen(merged, e);
        if (extent(merged) <= widest) {
          out.back() = merged;
          continue;
        }
      }
      out.push_back(e);
    }
    return out;
  }

  // The walk groups an envelope stands for: every group of its targets decides at each node
  // at least as strictly as these (a box at least as large, spline lengths at least as far
  // apart, the smallest |a_old|), one group per opening criterion its targets may use.
  std::vector<GravityTree::Group> envelope_groups(const Envelope& e) const {
    // Above the rounding of any group's box about its own centre.
    const double margin = 1e-9 * (cube_.side + std::fabs(cube_.centre.x) + std::fabs(cube_.centre.y) +
                                  std::fabs(cube_.centre.z));
    GravityTree::Group g;
    g.centre = 0.5 * (e.lo + e.hi);
    g.half = 0.5 * (e.hi - e.lo) + Vec3{margin, margin, margin};
    g.h_max = e.h_max;
    g.h_min = e.h_min;
    std::vector<GravityTree::Group> out;
    if (e.any_barnes_hut) {
      g.relative = false;
      out.push_back(g);
    }
    if (e.any_relative) {
      g.relative = true;
      g.a_crit = walk_config_.alpha_force * e.a_min;
      out.push_back(g);
    }
    return out;
  }

  // What of one held subtree the walks of `groups` may visit, in preorder: a node every group
  // passes by or accepts goes without its inside; one some group opens, with its children; one
  // some group lists, with its sources.
  // What of one own subtree a rank's batches may visit: its nodes and listed sources.
  struct ExportedBlock {
    std::vector<Exported> nodes;
    std::vector<SourceRecord> sources;
    std::size_t bytes() const {
      return 2 * sizeof(std::int64_t) + nodes.size() * sizeof(Exported) + sources.size() * sizeof(SourceRecord);
    }
  };

  ExportedBlock export_block(const Block& block, const std::vector<GravityTree::Group>& groups,
                             const GravityTree::WalkRules& rules) {
    ExportedBlock out;
    std::vector<std::int32_t> all(groups.size());
    for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<std::int32_t>(k);
    export_node(block.root, groups, all, rules, out.nodes, out.sources);
    counts_.nodes_sent += static_cast<std::int64_t>(out.nodes.size());
    counts_.sources_sent += static_cast<std::int64_t>(out.sources.size());
    return out;
  }

  void export_node(std::int32_t n, const std::vector<GravityTree::Group>& groups, const std::vector<std::int32_t>& active,
                   const GravityTree::WalkRules& rules, std::vector<Exported>& nodes, std::vector<SourceRecord>& sources) {
    const TreeNode& node = tree_.nodes_[static_cast<std::size_t>(n)];
    const std::size_t at = nodes.size();
    nodes.push_back({node, 1});
    std::vector<std::int32_t> opening;
    bool listed = false;
    GravityTree::NodeOffsets o;
    for (const std::int32_t k : active) {
      switch (tree_.decide(node, groups[static_cast<std::size_t>(k)], walk_config_, rules, o)) {
        case GravityTree::Visit::open:
          opening.push_back(k);
          break;
        case GravityTree::Visit::list:
          listed = true;
          break;
        case GravityTree::Visit::pruned:
          throw std::logic_error("TreeAcrossRanks: a rank's own subtree has a pruned node");
        default:
          break;
      }
    }
    if (!opening.empty()) {
      // The last child's `next` is its parent's.
      for (std::int32_t c = node.first_child; c >= 0 && c != node.next; c = tree_.nodes_[static_cast<std::size_t>(c)].next)
        export_node(c, groups, opening, rules, nodes, sources);
    } else if (listed) {
      nodes[at].node.first_child = -1;
      nodes[at].node.first = static_cast<std::int32_t>(sources.size());
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const auto u = static_cast<std::size_t>(k);
        sources.push_back({tree_.pos_[u], tree_.mass_[u], tree_.eps_[u], 0});
      }
    } else {
      nodes[at].node.first_child = TreeNode::kPruned;
    }
    nodes[at].subtree = static_cast<std::int32_t>(nodes.size() - at);
  }

  // Each rank sends every other rank what of its held subtrees that rank's batches may
  // visit.
  void exchange_essential_parts() {
    std::vector<char> message;
    MessageWriter w(message);
    for (const Envelope& e : envelopes()) w.put(e);
    const auto all = ranks_->allgather(message);
    // The rules of the whole tree's walk (its slack follows the root cube).
    TreeNode root;
    root.centre = cube_.centre;
    root.side = cube_.side;
    const GravityTree::WalkRules rules = GravityTree::walk_rules(walk_config_, root);
    std::vector<std::vector<char>> to(static_cast<std::size_t>(ranks_->size()));
    for (int q = 0; q < ranks_->size(); ++q) {
      if (q == ranks_->rank()) continue;
      std::vector<GravityTree::Group> groups;
      MessageReader in(all[static_cast<std::size_t>(q)]);
      for (std::size_t k = 0; k < all[static_cast<std::size_t>(q)].size() / sizeof(Envelope); ++k)
        for (const auto& g : envelope_groups(in.get<Envelope>())) groups.push_back(g);
      // In the order the receiver reads them: the top's preorder. The message is the largest
      // of a step (megabytes): made at its size from the blocks, each freed once written,
      // rather than grown by doubling.
      std::vector<ExportedBlock> blocks;
      std::size_t bytes = 0;
      for (const std::int32_t t : order_) {
        const TopNode& node = top_[static_cast<std::size_t>(t)];
        if (node.kind == Kind::held && node.owner == ranks_->rank()) {
          blocks.push_back(export_block(own_blocks_[static_cast<std::size_t>(node.part)], groups, rules));
          bytes += blocks.back().bytes();
        }
      }
      auto& out = to[static_cast<std::size_t>(q)];
      out.reserve(bytes);
      MessageWriter w(out);
      for (ExportedBlock& b : blocks) {
        w.put(static_cast<std::int64_t>(b.nodes.size()));
        w.put(static_cast<std::int64_t>(b.sources.size()));
        w.put(b.nodes.data(), b.nodes.size());
        w.put(b.sources.data(), b.sources.size());
        b = ExportedBlock{};
      }
      counts_.bytes_sent += static_cast<std::int64_t>(out.size());
    }
    received_ = ranks_->alltoall(std::move(to));
  }

  // The tree for this step's walks. Its first nodes and sources stay from the build: this
  // rank's own subtrees and the gathered ones (refitted in place). After them come, anew each
  // time, the top's nodes and the parts other ranks sent. The walk follows the links, not the
  // array order, so the links make the top's preorder: each node's `next` is where the preorder
  // goes after its subtree; then the top's moments are summed from the leaves up.
  void assemble() {
    tree_.nodes_.resize(prefix_nodes_);
    tree_.index_.resize(prefix_sources_);
    grow_sources(prefix_sources_);
    reserve_assembly();
    std::vector<MessageReader> in;
    for (const auto& m : received_) in.emplace_back(m);
    // Where each top node's subtree starts, and (received parts) its extent in the array.
    std::vector<std::int32_t> entry(top_.size(), -1), part_end(top_.size(), -1);
    std::vector<std::int32_t> top_internal;
    for (const std::int32_t t : order_) {
      const TopNode& top = top_[static_cast<std::size_t>(t)];
      const auto here = static_cast<std::int32_t>(tree_.nodes_.size());
      if (top.kind == Kind::internal) {
        TreeNode node;
        node.centre = node.built_centre = top.cube.centre;
        node.side = node.built_side = top.cube.side;
        node.count = static_cast<std::int32_t>(top.total);
        const std::int32_t at = t == 0 ? 0 : here;  // the root in its kept place
        if (t == 0)
          tree_.nodes_[0] = node;
        else
          tree_.nodes_.push_back(node);
        entry[static_cast<std::size_t>(t)] = at;
        top_internal.push_back(at);
        ++counts_.top_nodes;
      } else if (top.kind == Kind::gathered) {
        entry[static_cast<std::size_t>(t)] = gathered_blocks_[static_cast<std::size_t>(top.part)].root;
        ++counts_.top_nodes;
      } else if (top.owner == ranks_->rank()) {
        entry[static_cast<std::size_t>(t)] = own_blocks_[static_cast<std::size_t>(top.part)].root;
      } else {
        MessageReader& from = in[static_cast<std::size_t>(top.owner)];
        const auto node_count = from.get<std::int64_t>();
        const auto source_count = from.get<std::int64_t>();
        const auto first = static_cast<std::int32_t>(tree_.pos_.size());
        for (std::int64_t k = 0; k < node_count; ++k) {
          const auto e = from.get<Exported>();
          TreeNode node = e.node;
          const auto at = static_cast<std::int32_t>(tree_.nodes_.size());
          if (node.first_child >= 0) node.first_child = at + 1;
          if (node.first_child == -1) node.first += first;
          node.next = at + e.subtree;  // here + node_count: the part's end, linked below
          tree_.nodes_.push_back(node);
        }
        grow_sources(static_cast<std::size_t>(first) + static_cast<std::size_t>(source_count));
        for (std::int64_t k = 0; k < source_count; ++k) {
          const auto s = from.get<SourceRecord>();
          tree_.index_.push_back(kForeignSource);
          tree_.store_source(first + static_cast<std::int32_t>(k), kForeignSource, {s.x, s.mass, s.softening});
        }
        entry[static_cast<std::size_t>(t)] = here;
        part_end[static_cast<std::size_t>(t)] = here + static_cast<std::int32_t>(node_count);
        counts_.nodes_received += node_count;
        counts_.sources_received += source_count;
      }
    }
    // after[t]: the entry of the node the preorder reaches once t's subtree is done (-1: none).
    std::vector<std::size_t> subtree_end(top_.size());
    for (auto k = order_.size(); k-- > 0;) {
      const TopNode& top = top_[static_cast<std::size_t>(order_[k])];
      std::size_t end = k + 1;
      for (const std::int32_t c : top.child)
        if (c >= 0) end = std::max(end, subtree_end[static_cast<std::size_t>(c)]);
      subtree_end[static_cast<std::size_t>(order_[k])] = end;
    }
    auto after = [&](std::int32_t t) {
      const std::size_t end = subtree_end[static_cast<std::size_t>(t)];
      return end < order_.size() ? entry[static_cast<std::size_t>(order_[end])] : -1;
    };
    for (const std::int32_t t : order_) {
      const TopNode& top = top_[static_cast<std::size_t>(t)];
      const std::int32_t next = after(t);
      const std::int32_t at = entry[static_cast<std::size_t>(t)];
      if (top.kind == Kind::internal) {
        TreeNode& node = tree_.nodes_[static_cast<std::size_t>(at)];
        node.next = next;
        for (const std::int32_t c : top.child)
          if (c >= 0) {
            node.first_child = entry[static_cast<std::size_t>(c)];
            break;
          }
      } else if (top.kind == Kind::gathered || top.owner == ranks_->rank()) {
        const Block& block = top.kind == Kind::gathered ? gathered_blocks_[static_cast<std::size_t>(top.part)]
                                                        : own_blocks_[static_cast<std::size_t>(top.part)];
        for (const std::int32_t e : block.exits) tree_.nodes_[static_cast<std::size_t>(e)].next = next;
      } else {
        const std::int32_t end = part_end[static_cast<std::size_t>(t)];
        for (std::int32_t n = at; n < end; ++n)
          if (tree_.nodes_[static_cast<std::size_t>(n)].next == end) tree_.nodes_[static_cast<std::size_t>(n)].next = next;
      }
    }
    // Another rank's part as the whole tree: its root goes to node 0 (nothing links to it).
    if (top_[0].kind == Kind::held && top_[0].owner != ranks_->rank())
      tree_.nodes_[0] = tree_.nodes_[static_cast<std::size_t>(entry[0])];
    // A top node's content may spread while each of its parts stays tight (the parts drift
    // apart): as in one rank's tree, that makes the tree loose. Every rank computes these
    // nodes from the same parts, so all agree.
    for (auto t = top_internal.rbegin(); t != top_internal.rend(); ++t) loose_ = tree_.node_moments(*t) || loose_;
    release(received_);  // copied into the tree
  }

  // Room for what assemble() appends to the kept part, grown once to the size it needs (with
  // an eighth to spare for the next steps) rather than by doubling: the top's nodes and the
  // parts the other ranks sent, counted from their messages' headers.
  void reserve_assembly() {
    std::size_t nodes = 0, sources = 0;
    std::vector<MessageReader> in;
    for (const auto& m : received_) in.emplace_back(m);
    for (const std::int32_t t : order_) {
      const TopNode& top = top_[static_cast<std::size_t>(t)];
      if (top.kind == Kind::internal) {
        ++nodes;
      } else if (top.kind == Kind::held && top.owner != ranks_->rank()) {
        MessageReader& from = in[static_cast<std::size_t>(top.owner)];
        const auto node_count = static_cast<std::size_t>(from.get<std::int64_t>());
        const auto source_count = static_cast<std::size_t>(from.get<std::int64_t>());
        from.take(node_count * sizeof(Exported) + source_count * sizeof(SourceRecord));
        nodes += node_count;
        sources += source_count;
      }
    }
    const auto room = [](std::size_t n) { return n + n / 8; };
    if (tree_.nodes_.capacity() < prefix_nodes_ + nodes) tree_.nodes_.reserve(room(prefix_nodes_ + nodes));
    if (tree_.pos_.capacity() < prefix_sources_ + sources) {
      const std::size_t n = room(prefix_sources_ + sources);
      tree_.index_.reserve(n);
      tree_.pos_.reserve(n);
      for (auto* v : {&tree_.mass_, &tree_.spline_, &tree_.eps_}) v->reserve(n);
      tree_.spline_f_.reserve(n);
      tree_.spline_inv_f_.reserve(n);
    }
  }

  TreeMessages* ranks_ = nullptr;  // the present call's
  RankSources mine_;                // the present call's
  std::span<const TargetBatch> batches_;
  std::size_t own_count_ = 0;
  std::size_t kept_sources_ = 0;  // own and gathered sources, for the kept part's room
  bool has_sources_ = false, loose_ = false;
  TreeConfig tree_config_;
  WalkConfig walk_config_;
  std::int64_t gather_limit_ = 0;
  GravityTree::Cube cube_;
  std::vector<GravityTree::SortItem> items_, scratch_;
  std::vector<std::int32_t> gathered_members_;
  std::vector<TopNode> top_;
  std::vector<std::int32_t> order_;  // top_ in preorder
  GravityTree tree_;  // kept: the own and gathered blocks first, the rest made by each assembly
  std::vector<Block> own_blocks_, gathered_blocks_;
  std::size_t prefix_nodes_ = 0, prefix_sources_ = 0;
  std::vector<std::vector<char>> received_;
  TreeAcrossRanksCounts counts_;
};

TargetBatch::TargetBatch(std::span<const GravityTarget> targets) {
  if (targets.empty()) return;
  empty = false;
  lo = hi = targets[0].position;
  h_min = std::numeric_limits<double>::infinity();
  a_min = std::numeric_limits<double>::infinity();
  for (const GravityTarget& t : targets) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], t.position[d]);
      hi[d] = std::max(hi[d], t.position[d]);
    }
    h_max = std::max(h_max, spline_length(t.softening));
    h_min = std::min(h_min, spline_length(t.softening));
    if (t.a_old >= 0.0) {
      any_relative = true;
      a_min = std::min(a_min, t.a_old);
    } else {
      any_barnes_hut = true;
    }
  }
}

RankSources RankSources::of_arrays(std::span<const Vec3> positions, std::span<const double> masses,
                                  std::span<const double> softenings, std::span<const std::uint64_t> places,
                                  std::span<const std::int32_t> names) {
  if (masses.size() != positions.size() || softenings.size() != positions.size())
    throw std::invalid_argument("RankSources: positions, masses and softenings differ in length");
  RankSources s;
  s.count = positions.size();
  s.source = [positions, masses, softenings](std::size_t k) { return Source{positions[k], masses[k], softenings[k]}; };
  s.places = places;
  s.names = names;
  return s;
}

TreeAcrossRanks::TreeAcrossRanks(TreeMessages& ranks, const RankSources& mine, const TreeConfig& tree_config,
                                 const WalkConfig& walk_config)
    : impl_(std::make_unique<TreeAssembler>(ranks, mine, tree_config, walk_config)) {}
TreeAcrossRanks::~TreeAcrossRanks() = default;
TreeAcrossRanks::TreeAcrossRanks(TreeAcrossRanks&&) noexcept = default;
TreeAcrossRanks& TreeAcrossRanks::operator=(TreeAcrossRanks&&) noexcept = default;
void TreeAcrossRanks::refit(TreeMessages& ranks, const RankSources& mine) { impl_->refit(ranks, mine); }
bool TreeAcrossRanks::loose() const { return impl_->loose(); }
const GravityTree& TreeAcrossRanks::tree_for(TreeMessages& ranks, std::span<const TargetBatch> batches) {
  return impl_->tree_for(ranks, batches);
}
const TreeAcrossRanksCounts& TreeAcrossRanks::counts() const { return impl_->counts(); }
const GravityTree& TreeAcrossRanks::last_tree() const { return impl_->last_tree(); }

}  // namespace fountain::gravity
