#include "space/Space.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"

namespace fountain {

namespace {
constexpr int kMaxDepth = 24;
}

double Space::wrap_delta(double d, int dim) const {
  if (!config_.periodic) return d;
  const double L = size_[dim];
  if (d > 0.5 * L) return d - L;
  if (d < -0.5 * L) return d + L;
  return d;
}

double Space::box_distance(const Cell& a, const Cell& b) const {
  const Vec3 ca = a.centre(), cb = b.centre();
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::fabs(wrap_delta(cb[k] - ca[k], k));
    const double gap = std::max(0.0, d - 0.5 * (a.width[k] + b.width[k]));
    d2 += gap * gap;
  }
  return std::sqrt(d2);
}

namespace {

// Partitions order[first, first + count) by octant of `mid` (stable, so deterministic) and
// returns where each octant starts, relative to `first`.
std::array<std::size_t, 9> partition_octants(const std::vector<Vec3>& pos, std::size_t first, std::size_t count,
                                             const Vec3& mid, std::span<std::size_t> order,
                                             std::span<std::size_t> scratch) {
  std::array<std::size_t, 9> start{};
  auto octant = [&](std::size_t i) {
    const Vec3& x = pos[i];
    return (x.x >= mid.x ? 4 : 0) + (x.y >= mid.y ? 2 : 0) + (x.z >= mid.z ? 1 : 0);
  };
  for (std::size_t k = first; k < first + count; ++k) ++start[octant(order[k]) + 1];
  for (int o = 0; o < 8; ++o) start[o + 1] += start[o];
  std::array<std::size_t, 8> fill;
  for (int o = 0; o < 8; ++o) fill[o] = first + start[o];
  for (std::size_t k = first; k < first + count; ++k) {
    const std::size_t i = order[k];
    scratch[fill[octant(i)]++] = i;
  }
  std::copy(scratch.begin() + static_cast<std::ptrdiff_t>(first),
            scratch.begin() + static_cast<std::ptrdiff_t>(first + count),
            order.begin() + static_cast<std::ptrdiff_t>(first));
  return start;
}

Vec3 octant_corner(const Vec3& lo, const Vec3& half, int o) {
  return lo + Vec3{(o & 4) ? half.x : 0.0, (o & 2) ? half.y : 0.0, (o & 1) ? half.z : 0.0};
}

// Orders the particles of a leaf as the octree below it would (without making cells), so that
// any run of consecutive particles is spatially compact: the SPH loops work in small groups.
void order_leaf(const std::vector<Vec3>& pos, std::size_t first, std::size_t count, const Vec3& lo, const Vec3& width,
                int depth, std::span<std::size_t> order, std::span<std::size_t> scratch) {
  if (count <= 4 || depth >= kMaxDepth) return;
  const Vec3 half = width * 0.5;
  const std::array<std::size_t, 9> start = partition_octants(pos, first, count, lo + half, order, scratch);
  for (int o = 0; o < 8; ++o)
    if (start[o + 1] > start[o])
      order_leaf(pos, first + start[o], start[o + 1] - start[o], octant_corner(lo, half, o), half, depth + 1,
                 order, scratch);
}

}  // namespace

// The state of one top cell's build: its particles' positions, and its slices of the
// permutation being built for each species (indices into the positions).
struct Space::SortState {
  const std::vector<Vec3>& gas_x;
  const std::vector<Vec3>& dm_x;
  std::span<std::size_t> order, scratch, dm_order, dm_scratch;
  std::vector<Cell>& cells;  // the subtree; [0] is the top cell
};

void Space::rebuild(GasParticles& gas, CollisionlessParticles& dm, const ForEach& for_each) {
  recut(gas, dm, for_each);
  find_neighbours(for_each);
}

void Space::recut(GasParticles& gas, CollisionlessParticles& dm, const ForEach& for_each,
                  std::vector<std::size_t>* gas_order) {
  const std::size_t n = gas.size(), n_dm = dm.size();
  // The box: in a periodic one, every particle's image inside it.
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  if (config_.periodic) {
    for (std::vector<Vec3>* xs : {&gas.x, &dm.x})
      for (Vec3& p : *xs) p = wrap_into_box(p, config_.box_size);
  } else {
    for (const std::vector<Vec3>* xs : {&gas.x, &dm.x})
      for (const Vec3& p : *xs)
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], p[k]);
          hi[k] = std::max(hi[k], p[k]);
        }
  }
  set_frame(lo, hi, n, n_dm);
  const std::size_t ntot = cells_.size();

  // Stable counting sort by top cell: returns where each top cell starts and fills `order`.
  auto sort_by_top = [&](const std::vector<Vec3>& xs, std::vector<std::size_t>& order) {
    std::vector<std::size_t>& key = sort_key_;
    key.resize(xs.size());
    for (std::size_t i = 0; i < xs.size(); ++i) key[i] = static_cast<std::size_t>(top_cell_at(xs[i]));
    std::vector<std::size_t> start(ntot + 1, 0);
    for (std::size_t k : key) ++start[k + 1];
    for (std::size_t c = 0; c < ntot; ++c) start[c + 1] += start[c];
    order.resize(xs.size());  // every place is filled below
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < xs.size(); ++i) order[fill[key[i]]++] = i;
    return start;
  };
  sort_scratch_.resize(n);
  dm_sort_scratch_.resize(n_dm);
  const std::vector<std::size_t> start = sort_by_top(gas.x, sort_order_);
  const std::vector<std::size_t> dm_start = sort_by_top(dm.x, dm_sort_order_);
  for (std::size_t t = 0; t < ntot; ++t) {
    cells_[t].first = start[t];
    cells_[t].count = start[t + 1] - start[t];
    cells_[t].dm_first = dm_start[t];
    cells_[t].dm_count = dm_start[t + 1] - dm_start[t];
  }

  // Each top cell's octree and particle order come from its own particles alone (positions
  // are still in the original order: the builds read them through the orders), so top cells
  // go in parallel.
  std::vector<std::vector<Cell>> subtrees(ntot);
  auto slice = [](std::vector<std::size_t>& v, std::size_t first, std::size_t count) {
    return std::span<std::size_t>(v).subspan(first, count);
  };
  for_each_or_serial(for_each, ntot, [&](std::size_t t) {
    const Cell& top = cells_[t];
    subtrees[t] = build_subtree(top, gas.x, slice(sort_order_, top.first, top.count),
                                slice(sort_scratch_, top.first, top.count), dm.x,
                                slice(dm_sort_order_, top.dm_first, top.dm_count),
                                slice(dm_sort_scratch_, top.dm_first, top.dm_count));
  });
  assemble(subtrees);
  // The derived fields stay: each step's drift tasks and ghosts work them out before any read.
  gas.permute(sort_order_, for_each, &permute_scratch_, GasParticles::Derived::Stay);
  dm.permute(dm_sort_order_, for_each, &permute_scratch_);
  if (gas_order) gas_order->swap(sort_order_);

  // The leaves' h_max and speeds, from their particles.
  for (int c : leaves_) {
    Cell& cell = cells_[static_cast<std::size_t>(c)];
    for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
      cell.h_max = std::max(cell.h_max, gas.h[i]);
      cell.v_max = std::max(cell.v_max, norm(gas.v_full[i]));
    }
  }
  set_covers();
}

void Space::set_frame(const Vec3& lo, const Vec3& hi, std::size_t n, std::size_t n_dm) {
  ++rebuilds_;
  if (config_.periodic) {
    lo_ = {};
    size_ = config_.box_size;
  } else {
    // The particles' bounding box, a little wider (and never flat).
    Vec3 a = lo, b = hi;
    if (n + n_dm == 0) a = b = {};
    double ext = 0.0;
    for (int k = 0; k < 3; ++k) ext = std::max(ext, b[k] - a[k]);
    if (ext == 0.0) ext = 1.0;
    for (int k = 0; k < 3; ++k) {
      const double e = std::max(b[k] - a[k], 1e-3 * ext) * (1.0 + 1e-6) + 1e-12 * ext;
      lo_[k] = a[k] - 0.5 * (e - (b[k] - a[k]));
      size_[k] = e;
    }
  }

  // Top-level grid.
  std::array<int, 3> ntop{1, 1, 1};
  {
    const double longest = std::max({size_.x, size_.y, size_.z});
    double w;
    if (config_.top_cells > 0) {
      w = longest / config_.top_cells;
    } else {
      const double volume = size_.x * size_.y * size_.z;
      w = std::cbrt(volume * 4.0 * config_.split_size / std::max<double>(1.0, static_cast<double>(std::max(n, n_dm))));
    }
    // In a periodic box a cell wider than a quarter of the box's shortest side is split (see
    // split()): top cells that start that narrow are not split for it, which would cut sparse
    // regions (Sod's low-density half) into leaves of a few tens of particles with long
    // neighbour lists.
    if (config_.periodic) w = std::min(w, 0.25 * std::min({size_.x, size_.y, size_.z}));
    for (int k = 0; k < 3; ++k) ntop[k] = std::clamp(static_cast<int>(std::floor(size_[k] / w)), 1, kMaxTopPerAxis);
  }
  ntop_ = ntop;
  const Vec3 wtop{size_.x / ntop[0], size_.y / ntop[1], size_.z / ntop[2]};
  const std::size_t ntot = static_cast<std::size_t>(ntop[0]) * ntop[1] * ntop[2];
  // Empty top cells cost memory and a place in every neighbour search: a grid finer than one
  // cell per particle (judged once, at the first cut: star formation changes the counts a little)
  // only slows the run, by orders of magnitude at 64^3 cells for a thousand particles.
  if (config_.top_cells > 0 && rebuilds_ == 1 && ntot > std::max<std::size_t>(kFewestTopCellsAllowed, n + n_dm))
    throw InputError(fmt::format("{} = {} makes {} x {} x {} = {} top-level cells for {} particles: "
                                 "at most one cell per particle is allowed; lower it, or set 0 to choose from the "
                                 "particle number",
                                 config_.top_cells_origin, config_.top_cells, ntop[0], ntop[1], ntop[2], ntot, n + n_dm));
  cells_.clear();
  top_.clear();
  leaves_.clear();
  for (int a = 0; a < ntop[0]; ++a)
    for (int b = 0; b < ntop[1]; ++b)
      for (int c = 0; c < ntop[2]; ++c) {
        Cell cell;
        cell.lo = lo_ + Vec3{a * wtop.x, b * wtop.y, c * wtop.z};
        cell.width = wtop;
        cells_.push_back(cell);
        top_.push_back(static_cast<int>(cells_.size()) - 1);
      }
  half_ = size_ * 0.5;
}

void Space::assemble(const std::vector<std::vector<Cell>>& subtrees) {
  // The cells are numbered as one depth-first walk of the top cells in grid order would number
  // them; particle ranges count from each top cell's first particle.
  const std::size_t ntot = top_.size();
  for (std::size_t t = 0; t < ntot; ++t) {
    const std::vector<Cell>& sub = subtrees[t];
    const int base = static_cast<int>(cells_.size()) - 1;  // subtree cell k >= 1 becomes base + k
    auto renumber = [&](int k) { return k <= 0 ? (k == 0 ? static_cast<int>(t) : -1) : base + k; };
    Cell& top = cells_[t];  // (the pushes below move the cells: read it first)
    top.leaf = sub[0].leaf;
    top.h_max = sub[0].h_max;
    top.v_max = sub[0].v_max;
    top.ti_end_min = sub[0].ti_end_min;
    for (int o = 0; o < 8; ++o) top.children[static_cast<std::size_t>(o)] = renumber(sub[0].children[static_cast<std::size_t>(o)]);
    const std::size_t first = top.first, dm_first = top.dm_first;
    for (std::size_t k = 1; k < sub.size(); ++k) {
      Cell cell = sub[k];
      cell.first += first;
      cell.dm_first += dm_first;
      cell.parent = renumber(cell.parent);
      for (int& ch : cell.children) ch = renumber(ch);
      cells_.push_back(cell);
    }
  }
  // The leaves that hold particles (only the cells are needed for that).
  leaves_.clear();
  leaf_slot_.assign(cells_.size(), -1);
  for (int c = 0; c < static_cast<int>(cells_.size()); ++c)
    if (cells_[static_cast<std::size_t>(c)].leaf &&
        cells_[static_cast<std::size_t>(c)].count + cells_[static_cast<std::size_t>(c)].dm_count > 0) {
      leaf_slot_[static_cast<std::size_t>(c)] = static_cast<int>(leaves_.size());
      leaves_.push_back(c);
    }
}

void Space::set_covers() {
  // The leaves' cover radii from their h_max; inner nodes take the largest cover below them.
  for (int c = static_cast<int>(cells_.size()) - 1; c >= 0; --c) {
    Cell& cell = cells_[static_cast<std::size_t>(c)];
    cell.dx_max = 0.0;
    cell.dx_around = 0.0;
    if (cell.leaf) {
      cell.r_cover = (1.0 + config_.skin) * cell.h_max;
    } else {
      cell.r_cover = 0.0;
      cell.h_max = 0.0;
      for (int ch : cell.children)
        if (ch >= 0) {
          cell.r_cover = std::max(cell.r_cover, cells_[static_cast<std::size_t>(ch)].r_cover);
          cell.h_max = std::max(cell.h_max, cells_[static_cast<std::size_t>(ch)].h_max);
        }
    }
  }
  if (config_.periodic) {
    // One image of each neighbour, the one nearest the cell, must suffice: the reach from
    // a cell's centre stays below half the box.
    double reach = 0.0;
    for (int c : leaves_) {
      const Cell& cell = cells_[static_cast<std::size_t>(c)];
      reach = std::max(reach, cell.r_cover + 0.5 * std::max({cell.width.x, cell.width.y, cell.width.z}));
    }
    const double half = 0.5 * std::min({size_.x, size_.y, size_.z});
    if (reach >= half)
      throw InputError(fmt::format(
          "periodic box of size {} x {} x {} is too small for smoothing lengths up to {}: "
          "use more particles or a smaller neighbour number",
          size_.x, size_.y, size_.z, reach / (1.0 + config_.skin)));
  }
}

void Space::find_neighbours(const ForEach& for_each) { find_neighbours(for_each, 0, leaves_.size()); }

void Space::set_lists(std::size_t l, std::span<const int> neighbours, std::span<const int> surroundings) {
  neighbours_[l].assign(neighbours.begin(), neighbours.end());
  surroundings_[l].assign(surroundings.begin(), surroundings.end());
}

void Space::find_neighbours(const ForEach& for_each, std::size_t first, std::size_t last) {
  neighbours_.assign(leaves_.size(), {});
  surroundings_.assign(leaves_.size(), {});
  last = std::min(last, leaves_.size());
  first = std::min(first, last);
  // A top cell's cover bounds those of its leaves, so no leaf of a top cell farther than
  // the largest top cover (or a leaf's surroundings reach) from a leaf is on its lists: only
  // the top cells within that reach are walked, in the grid's order, as the whole grid was
  // (walking every top cell for every leaf made the lists O(leaves x top cells)).
  double top_cover = 0.0;
  for (int t : top_) top_cover = std::max(top_cover, cells_[static_cast<std::size_t>(t)].r_cover);
  const std::function<void(std::size_t)> lists_of = [this, top_cover, first](std::size_t k) {
    const std::size_t l = first + k;
    const Cell& a = cells_[static_cast<std::size_t>(leaves_[l])];
    if (a.count == 0) return;
    const double reach = std::max(surroundings_reach(a), top_cover);
    std::array<TopRange, 3> range;
    for (int k = 0; k < 3; ++k) range[static_cast<std::size_t>(k)] = top_range(a, reach, k);
    for (int i = 0; i < range[0].count; ++i)
      for (int j = 0; j < range[1].count; ++j)
        for (int m = 0; m < range[2].count; ++m) {
          const int t = (range[0].index[static_cast<std::size_t>(i)] * ntop_[1] + range[1].index[static_cast<std::size_t>(j)]) * ntop_[2] +
                        range[2].index[static_cast<std::size_t>(m)];
          collect_leaves(leaves_[l], top_[static_cast<std::size_t>(t)], neighbours_[l], surroundings_[l]);
        }
  };
  for_each_or_serial(for_each, last - first, lists_of);
}


std::vector<Cell> Space::build_subtree(const Cell& top, const std::vector<Vec3>& gas_x, std::span<std::size_t> gas_order,
                                      std::span<std::size_t> gas_scratch, const std::vector<Vec3>& dm_x,
                                      std::span<std::size_t> dm_order, std::span<std::size_t> dm_scratch) const {
  std::vector<Cell> cells(1);
  Cell& root = cells[0];
  root.lo = top.lo;
  root.width = top.width;
  root.first = 0;
  root.count = gas_order.size();
  root.dm_first = 0;
  root.dm_count = dm_order.size();
  root.depth = top.depth;
  SortState s{gas_x, dm_x, gas_order, gas_scratch, dm_order, dm_scratch, cells};
  split(0, s);
  // Each leaf's particles are ordered within its own range of the orders.
  for (const Cell& cell : cells) {
    if (!cell.leaf) continue;
    order_leaf(gas_x, cell.first, cell.count, cell.lo, cell.width, cell.depth, gas_order, gas_scratch);
    order_leaf(dm_x, cell.dm_first, cell.dm_count, cell.lo, cell.width, cell.depth, dm_order, dm_scratch);
  }
  return cells;
}

void Space::split(int c, SortState& s) const {
  const Cell cell = s.cells[static_cast<std::size_t>(c)];
  const std::size_t limit = static_cast<std::size_t>(config_.split_size);
  bool must_split = cell.count > limit || cell.dm_count > limit;
  if (config_.periodic && cell.count + cell.dm_count > 1) {
    // Keep leaves small against the box so the nearest image of cell centres is that of their boxes.
    for (int k = 0; k < 3; ++k) must_split = must_split || cell.width[k] > 0.25 * size_[k];
  }
  if (!must_split || cell.depth >= kMaxDepth) return;  // a leaf: its particles are ordered later

  const std::array<std::size_t, 9> start = partition_octants(s.gas_x, cell.first, cell.count, cell.centre(), s.order, s.scratch);
  const std::array<std::size_t, 9> dm_start =
      partition_octants(s.dm_x, cell.dm_first, cell.dm_count, cell.centre(), s.dm_order, s.dm_scratch);
  s.cells[static_cast<std::size_t>(c)].leaf = false;
  for (int o = 0; o < 8; ++o) {
    const std::size_t cnt = start[o + 1] - start[o], dm_cnt = dm_start[o + 1] - dm_start[o];
    if (cnt + dm_cnt == 0) continue;
    Cell child;
    child.width = cell.width * 0.5;
    child.lo = octant_corner(cell.lo, child.width, o);
    child.first = cell.first + start[o];
    child.count = cnt;
    child.dm_first = cell.dm_first + dm_start[o];
    child.dm_count = dm_cnt;
    child.parent = c;
    child.depth = cell.depth + 1;
    s.cells.push_back(child);
    const int id = static_cast<int>(s.cells.size()) - 1;
    s.cells[static_cast<std::size_t>(c)].children[o] = id;
    split(id, s);
  }
}

int Space::top_cell_at(const Vec3& x) const {
  std::array<int, 3> ix;
  for (int k = 0; k < 3; ++k)
    ix[k] = std::clamp(static_cast<int>(std::floor((x[k] - lo_[k]) / (size_[k] / ntop_[k]))), 0, ntop_[k] - 1);
  return (ix[0] * ntop_[1] + ix[1]) * ntop_[2] + ix[2];
}

int Space::cell_at(const Vec3& x) const {
  int c = top_cell_at(x);
  for (;;) {
    const Cell& cell = cells_[static_cast<std::size_t>(c)];
    if (cell.leaf) return c;
    int next = -1;
    for (int ch : cell.children) {
      if (ch < 0) continue;
      const Cell& b = cells_[static_cast<std::size_t>(ch)];
      bool inside = true;
      for (int k = 0; k < 3; ++k) inside = inside && x[k] >= b.lo[k] && x[k] < b.lo[k] + b.width[k];
      if (inside) next = ch;
    }
    if (next < 0) return c;
    c = next;
  }
}

Space::TopRange Space::top_range(const Cell& a, double reach, int k) const {
  // A margin of 1e-6 of a top cell absorbs rounding: a top cell listed here and beyond
  // reach is only walked for nothing; box_distance decides.
  const int n = ntop_[static_cast<std::size_t>(k)];
  const double w = size_[k] / n, margin = 1e-6 * w;
  const double from = a.lo[k] - lo_[k] - reach - margin, to = a.lo[k] - lo_[k] + a.width[k] + reach + margin;
  const long first = static_cast<long>(std::floor(from / w)), last = static_cast<long>(std::floor(to / w));
  TopRange r;
  if (last - first + 1 >= n) {
    for (int i = 0; i < n; ++i) r.index[static_cast<std::size_t>(r.count++)] = i;
  } else if (config_.periodic) {
    // Nearest images: a range past either edge of the box continues on the other side.
    for (long i = first; i <= last; ++i) r.index[static_cast<std::size_t>(r.count++)] = static_cast<int>(((i % n) + n) % n);
    std::sort(r.index.begin(), r.index.begin() + r.count);
  } else {
    for (long i = std::max(first, 0L); i <= std::min(last, static_cast<long>(n) - 1); ++i)
      r.index[static_cast<std::size_t>(r.count++)] = static_cast<int>(i);
  }
  return r;
}

// Leaves with gas below `node` whose boxes lie within reach of leaf `leaf`'s: its neighbours
// (reach: the larger cover radius of the two; an inner node's cover bounds its leaves') and
// its surroundings (reach: surroundings_reach of the leaf), both in one walk.
void Space::collect_leaves(int leaf, int node, std::vector<int>& neighbours, std::vector<int>& surroundings) const {
  const Cell& a = cells_[static_cast<std::size_t>(leaf)];
  const Cell& b = cells_[static_cast<std::size_t>(node)];
  if (b.count == 0) return;
  const double d = box_distance(a, b);
  const bool neighbour = d < std::max(a.r_cover, b.r_cover), around = d < surroundings_reach(a);
  if (!neighbour && !around) return;
  if (b.leaf) {
    if (node == leaf) return;
    if (neighbour) neighbours.push_back(node);
    if (around) surroundings.push_back(node);
    return;
  }
  for (int ch : b.children)
    if (ch >= 0) collect_leaves(leaf, ch, neighbours, surroundings);
}

}  // namespace fountain
