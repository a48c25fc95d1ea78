#include "gravity/GravityTree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace fountain::gravity {

namespace {

// The traceless quadrupole of a point mass m at offset d: m (3 d d^T - |d|^2 I).
void add_point_quadrupole(std::array<double, 6>& q, double m, const Vec3& d) {
  const double d2 = dot(d, d);
  q[0] += m * (3.0 * d.x * d.x - d2);
  q[1] += m * (3.0 * d.y * d.y - d2);
  q[2] += m * (3.0 * d.z * d.z - d2);
  q[3] += m * 3.0 * d.x * d.y;
  q[4] += m * 3.0 * d.x * d.z;
  q[5] += m * 3.0 * d.y * d.z;
}

double farthest(const Vec3& d) { return std::max({std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)}); }

void check_source(std::size_t i, const Vec3& x, double mass, double softening) {
  if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z) || !std::isfinite(mass) || mass < 0.0 ||
      !std::isfinite(softening) || softening < 0.0)
    throw std::invalid_argument("GravityTree: source " + std::to_string(i) +
                                " has a non-finite position or a negative/non-finite mass or softening");
}

void check_inputs(std::span<const Vec3> positions, std::span<const double> masses,
                  std::span<const double> softenings, const TreeConfig& config) {
  if (masses.size() != positions.size() || softenings.size() != positions.size())
    throw std::invalid_argument("GravityTree: positions, masses and softenings differ in length");
  if (positions.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument("GravityTree: too many sources for 32-bit node ranges");
  if (config.max_leaf_size < 1) throw std::invalid_argument("GravityTree: max_leaf_size must be >= 1");
  if (config.periodic && !(config.box_size > 0.0 && std::isfinite(config.box_size)))
    throw std::invalid_argument("GravityTree: a periodic tree needs a positive box size");
  // Each source is checked as it is stored (store_source).
}

}  // namespace

GravityTree::Cube GravityTree::root_cube(const Vec3& lo, const Vec3& hi) {
  double side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  // A hair of margin keeps particles on the upper faces inside the cube after rounding.
  side = side > 0.0 ? side * (1.0 + 1e-9) : 1.0;
  return {0.5 * (lo + hi), side};
}

GravityTree::GravityTree(std::span<const Vec3> positions, std::span<const double> masses,
                         std::span<const double> softenings, const TreeConfig& config)
    : config_(config) {
  check_inputs(positions, masses, softenings, config);
  if (positions.empty()) return;
  Vec3 lo = positions[0], hi = positions[0];
  for (const Vec3& x : positions)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], x[d]);
      hi[d] = std::max(hi[d], x[d]);
    }
  build_from(positions, masses, softenings, root_cube(lo, hi), 0);
}

GravityTree::GravityTree(std::span<const Vec3> positions, std::span<const double> masses,
                         std::span<const double> softenings, const TreeConfig& config, const Cube& cube, int depth)
    : config_(config) {
  check_inputs(positions, masses, softenings, config);
  if (!positions.empty()) build_from(positions, masses, softenings, cube, depth);
}

void GravityTree::build_from(std::span<const Vec3> positions, std::span<const double> masses,
                             std::span<const double> softenings, const Cube& cube, int depth) {
  const auto n = static_cast<std::int32_t>(positions.size());
  index_.resize(static_cast<std::size_t>(n));
  length_unit_ = std::ldexp(1.0, std::ilogb(cube.side));

  // Partitioned with their positions beside their indices, so no pass reads through an index.
  std::vector<SortItem> items(static_cast<std::size_t>(n)), scratch(static_cast<std::size_t>(n));
  for (std::int32_t i = 0; i < n; ++i) items[static_cast<std::size_t>(i)] = {positions[i], i};
  nodes_.reserve(node_estimate(static_cast<std::size_t>(n), config_.max_leaf_size));
  build(0, n, cube.centre, cube.side, depth, items, scratch);
  for (TreeNode& node : nodes_)
    if (node.next == static_cast<std::int32_t>(nodes_.size())) node.next = -1;

  for (std::int32_t k = 0; k < n; ++k) index_[k] = items[static_cast<std::size_t>(k)].index;
  load_sources(positions, masses, softenings);
  compute_moments();
  plan_refit_groups();
}

void GravityTree::refit(std::span<const Vec3> positions, std::span<const double> masses,
                        std::span<const double> softenings) {
  check_inputs(positions, masses, softenings, config_);
  if (positions.size() != index_.size())
    throw std::invalid_argument("GravityTree::refit: " + std::to_string(positions.size()) + " sources for a tree of " +
                                std::to_string(index_.size()));
  const auto fetch = [&](std::size_t i) { return RefitSource{positions[i], masses[i], softenings[i]}; };
  for (int g = 0; g < kRefitGroups; ++g) refit_group(g, fetch);
  finish_refit();
}

// The sources in tree order, with what the walk derives from their softenings.
void GravityTree::load_sources(std::span<const Vec3> positions, std::span<const double> masses,
                               std::span<const double> softenings) {
  const std::size_t n = index_.size();
  pos_.resize(n);
  mass_.resize(n);
  spline_.resize(n);
  spline_f_.resize(n);
  spline_inv_f_.resize(n);
  eps_.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(index_[k]);
    store_source(static_cast<std::int32_t>(k), static_cast<std::int32_t>(i), {positions[i], masses[i], softenings[i]});
  }
}

void GravityTree::store_source(std::int32_t k, std::int32_t i, const RefitSource& s) {
  check_source(static_cast<std::size_t>(i), s.x, s.mass, s.softening);
  const auto u = static_cast<std::size_t>(k);
  pos_[u] = s.x;
  mass_[u] = s.mass;
  eps_[u] = s.softening;
  spline_[u] = spline_length(s.softening);
  spline_f_[u] = static_cast<float>(spline_[u] / length_unit_);
  spline_inv_f_[u] = 1.0f / spline_f_[u];
}

// Subtrees of at most 1/(2 kRefitGroups) of the particles become pieces (a leaf is one
// whatever its size); the nodes above them are refitted last. Pieces are dealt to groups in
// preorder, a group closing once it holds its share of the particles.
void GravityTree::plan_refit_groups() {
  pieces_.clear();
  top_nodes_.clear();
  group_start_.fill(0);
  group_loose_.fill(false);
  if (nodes_.empty()) return;
  const std::int64_t n = static_cast<std::int64_t>(index_.size());
  const std::int64_t piece_size = std::max<std::int64_t>(1, n / (2 * kRefitGroups));
  for (std::int32_t k = 0; k < static_cast<std::int32_t>(nodes_.size());) {
    const TreeNode& node = nodes_[static_cast<std::size_t>(k)];
    if (node.first_child < 0 || node.count <= piece_size) {
      pieces_.push_back(k);
      k = node.next < 0 ? static_cast<std::int32_t>(nodes_.size()) : node.next;  // past its subtree
    } else {
      top_nodes_.push_back(k);
      ++k;  // into its children
    }
  }
  std::int64_t dealt = 0;
  int g = 0;
  for (std::size_t p = 0; p < pieces_.size(); ++p) {
    dealt += nodes_[static_cast<std::size_t>(pieces_[p])].count;
    while (g < kRefitGroups - 1 && dealt * kRefitGroups >= n * (g + 1))
      group_start_[static_cast<std::size_t>(++g)] = static_cast<std::int32_t>(p + 1);
  }
  while (g < kRefitGroups) group_start_[static_cast<std::size_t>(++g)] = static_cast<std::int32_t>(pieces_.size());
}

bool GravityTree::piece_moments(std::int32_t root) {
  const std::int32_t next = nodes_[static_cast<std::size_t>(root)].next;
  const std::int32_t end = next < 0 ? static_cast<std::int32_t>(nodes_.size()) : next;
  bool loose = false;
  for (std::int32_t k = end - 1; k >= root; --k) loose = node_moments(k) || loose;
  return loose;
}

std::int64_t GravityTree::refit_group_count(int g) const {
  std::int64_t count = 0;
  for (std::int32_t p = group_start_[static_cast<std::size_t>(g)]; p < group_start_[static_cast<std::size_t>(g) + 1]; ++p)
    count += nodes_[static_cast<std::size_t>(pieces_[static_cast<std::size_t>(p)])].count;
  return count;
}

void GravityTree::check_refittable() const {
  if (across_ranks_)
    throw std::logic_error("GravityTree: a tree assembled across ranks is assembled anew, not refitted");
}

void GravityTree::finish_refit() {
  check_refittable();
  bool loose = false;
  for (bool l : group_loose_) loose = loose || l;
  for (auto t = top_nodes_.rbegin(); t != top_nodes_.rend(); ++t) loose = node_moments(*t) || loose;
  loose_ = loose;
}

// Sequential depth-first build of the topology: nodes come out in preorder, so a node's first
// child is the next node and its subtree ends where `next` points. Partitions are stable
// counting sorts, so the tree depends only on the input order.
void GravityTree::build(std::int32_t first, std::int32_t count, const Vec3& centre, double side, int depth,
                        std::vector<SortItem>& items, std::vector<SortItem>& scratch) {
  const auto self = static_cast<std::int32_t>(nodes_.size());
  TreeNode node;
  node.centre = node.built_centre = centre;
  node.side = side;
  node.built_side = side;
  node.first = first;
  node.count = count;
  nodes_.push_back(node);

  if (count > config_.max_leaf_size && depth < kMaxDepth) {
    std::array<std::int32_t, 9> start{};
    for (std::int32_t k = first; k < first + count; ++k) ++start[octant(items[k].x, centre) + 1];
    for (int o = 0; o < 8; ++o) start[o + 1] += start[o];
    std::array<std::int32_t, 8> fill{};
    for (std::int32_t k = first; k < first + count; ++k) {
      const int o = octant(items[k].x, centre);
      scratch[first + start[o] + fill[o]++] = items[k];
    }
    std::copy(scratch.begin() + first, scratch.begin() + first + count, items.begin() + first);

    nodes_[self].first_child = self + 1;
    const double child_side = 0.5 * side;
    for (int o = 0; o < 8; ++o) {
      const std::int32_t child_count = start[o + 1] - start[o];
      if (child_count == 0) continue;
      build(first + start[o], child_count, child_centre(centre, side, o), child_side, depth + 1, items, scratch);
    }
  }
  nodes_[self].next = static_cast<std::int32_t>(nodes_.size());
}

// Moments from the leaves up (children follow their parent in preorder, so a reverse pass
// meets every child first): a leaf sums its particles, a parent combines its children's
// moments about its own centre of mass (the parallel-axis shift of each child's quadrupole).
// Each cube keeps its centre and grows from its built side just enough to hold what is
// inside: a leaf its particles, a parent its children's cubes (only once one of them has
// grown: built children tile their parent).
void GravityTree::compute_moments() {
  bool loose = false;
  for (auto n = static_cast<std::int32_t>(nodes_.size()) - 1; n >= 0; --n) loose = node_moments(n) || loose;
  loose_ = loose;
}

bool GravityTree::node_moments(std::int32_t n) {
  TreeNode& node = nodes_[static_cast<std::size_t>(n)];
  auto& q = node.quadrupole;
  q = {};
  node.mass = 0.0;
  node.max_softening = 0.0;
  node.min_softening = std::numeric_limits<double>::infinity();
  node.second_moment = 0.0;
  node.centre = node.built_centre;
  node.side = node.built_side;
  Vec3 weighted;
  double reach = 0.0;  // without fit_cubes: how far from the centre the content extends
  bool grown = false;
  // The box around the node's content: the particles, or the children's boxes.
  constexpr double inf = std::numeric_limits<double>::infinity();
  Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
  auto enclose = [&](const Vec3& a, const Vec3& b) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], a[d]);
      hi[d] = std::max(hi[d], b[d]);
    }
  };
  // The built cube while it holds the box; otherwise, with fit_cubes, the cube about the box,
  // no smaller than the built one and grown by a margin for the rounding of the box's
  // midpoint (a larger cube only opens more). Without, see below.
  auto fit_cube = [&] {
    node.content_lo = lo;
    node.content_hi = hi;
    if (!config_.fit_cubes || !(lo.x <= hi.x)) return;  // (or no content)
    const double content_reach = std::max(farthest(lo - node.built_centre), farthest(hi - node.built_centre));
    if (2.0 * content_reach <= node.built_side) return;
    node.centre = 0.5 * (lo + hi);
    node.side = std::max(node.built_side, farthest(hi - lo)) * (1.0 + 1e-12);
  };
  if (node.first_child < 0) {
    for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
      node.mass += mass_[k];
      weighted += mass_[k] * pos_[k];
      node.max_softening = std::max(node.max_softening, eps_[static_cast<std::size_t>(k)]);
      node.min_softening = std::min(node.min_softening, eps_[static_cast<std::size_t>(k)]);
      enclose(pos_[k], pos_[k]);
      if (!config_.fit_cubes) reach = std::max(reach, farthest(pos_[k] - node.centre));
    }
    fit_cube();
    // The cube grown about its built centre until it holds the particles.
    if (!config_.fit_cubes) node.side = std::max(node.side, 2.0 * reach);
    // A massless node still needs a finite position for the distance tests.
    node.com = node.mass > 0.0 ? weighted * (1.0 / node.mass) : node.centre;
    for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
      const Vec3 s = pos_[k] - node.com;
      add_point_quadrupole(q, mass_[k], s);
      node.second_moment += mass_[k] * dot(s, s);
    }
    if (node.count == 0) node.min_softening = 0.0;
    return node.side > 2.0 * node.built_side;
  }
  // The last child's `next` is its parent's (a tree assembled across ranks keeps some subtrees
  // apart from the preorder of the array, so the children are found by the links alone).
  for (std::int32_t c = node.first_child; c >= 0 && c != node.next; c = nodes_[c].next) {
    const TreeNode& child = nodes_[c];
    node.mass += child.mass;
    weighted += child.mass * child.com;
    node.max_softening = std::max(node.max_softening, child.max_softening);
    node.min_softening = std::min(node.min_softening, child.min_softening);
    enclose(child.content_lo, child.content_hi);
    if (!config_.fit_cubes) {
      reach = std::max(reach, farthest(child.centre - node.centre) + 0.5 * child.side);
      grown = grown || child.side != child.built_side;
    }
  }
  if (!(node.min_softening <= node.max_softening)) node.min_softening = 0.0;  // no child
  fit_cube();
  // The cube grown about its built centre to hold its children's once one has grown; the
  // margin covers the rounding of the sum above.
  if (grown) node.side = std::max(node.side, 2.0 * reach * (1.0 + 1e-12));
  node.com = node.mass > 0.0 ? weighted * (1.0 / node.mass) : node.centre;
  for (std::int32_t c = node.first_child; c >= 0 && c != node.next; c = nodes_[c].next) {
    const TreeNode& child = nodes_[c];
    for (int m = 0; m < 6; ++m) q[m] += child.quadrupole[m];
    const Vec3 s = child.com - node.com;
    add_point_quadrupole(q, child.mass, s);
    node.second_moment += child.second_moment + child.mass * dot(s, s);
  }
  return node.side > 2.0 * node.built_side;
}
}  // namespace fountain::gravity
