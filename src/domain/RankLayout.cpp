#include "domain/RankLayout.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "domain/DomainDecomposition.hpp"

namespace fountain::domain {

bool RankLayout::holds(int r, int c) const {
  const auto& h = holders_[static_cast<std::size_t>(c)];
  return std::binary_search(h.begin(), h.end(), r);
}

void RankLayout::find_holders(const Space& space) {
  // A leaf's tasks read its neighbours, and neighbourhood is symmetric (the larger cover of
  // the two decides), so the ranks that read a leaf are the owners of its neighbours.
  const std::size_t ncells = space.cells().size();
  holders_.assign(ncells, {});
  held_.assign(ncells, 0);
  for (int c : space.leaves()) {
    auto& h = holders_[static_cast<std::size_t>(c)];
    h.push_back(owner_[static_cast<std::size_t>(c)]);
    for (int n : space.neighbours(c)) h.push_back(owner_[static_cast<std::size_t>(n)]);
    std::sort(h.begin(), h.end());
    h.erase(std::unique(h.begin(), h.end()), h.end());
    held_[static_cast<std::size_t>(c)] = std::binary_search(h.begin(), h.end(), rank_);
    leaves_held_ += held_[static_cast<std::size_t>(c)];
  }
  leaves_seen_ += static_cast<long long>(space.leaves().size());
}

void RankLayout::assign_owners(const Space& space, const std::vector<std::pair<Vec3, double>>& measured,
                               long long steps) {
  // Owners are chosen per leaf, not per top-level cell: every rank holds every particle, so
  // the grain of the cut is free, and the top-level grid (which changes the results, bit by
  // bit) need not depend on the rank count.
  const std::vector<int>& leaves = space.leaves();
  const std::size_t nl = leaves.size();
  std::vector<Vec3> centres(nl);
  std::vector<double> counts(nl);
  std::vector<int> slot(space.cells().size(), -1);
  for (std::size_t l = 0; l < nl; ++l) {
    const Cell& cell = space.cell(leaves[l]);
    centres[l] = cell.centre();
    counts[l] = static_cast<double>(cell.count + cell.dm_count);
    slot[static_cast<std::size_t>(leaves[l])] = static_cast<int>(l);
  }
  const std::vector<int> leaf_owner = cut_along_curve(space, centres, counts, measured, steps, [&](const Vec3& x) {
    int c = space.cell_at(x);
    while (!space.cell(c).leaf) {  // an empty octant: the first leaf below stands in
      int next = -1;
      for (int ch : space.cell(c).children)
        if (ch >= 0 && next < 0) next = ch;
      c = next;
    }
    return static_cast<std::size_t>(slot[static_cast<std::size_t>(c)]);
  });
  owner_.assign(space.cells().size(), 0);
  for (std::size_t l = 0; l < nl; ++l) owner_[static_cast<std::size_t>(leaves[l])] = leaf_owner[l];
  cost_.assign(space.cells().size(), 0.0);
}

std::vector<int> RankLayout::assign_top_owners(const Space& space, const std::vector<double>& counts,
                                               const std::vector<std::pair<Vec3, double>>& measured, long long steps) {
  const std::size_t ntop = counts.size();
  std::vector<Vec3> centres(ntop);
  for (std::size_t t = 0; t < ntop; ++t) centres[t] = space.cell(static_cast<int>(t)).centre();
  top_owner_ = cut_along_curve(space, centres, counts, measured, steps,
                               [&](const Vec3& x) { return static_cast<std::size_t>(space.top_cell_at(x)); });
  return top_owner_;
}

void RankLayout::set_owners_from_tops(const Space& space) {
  owner_.assign(space.cells().size(), 0);
  for (std::size_t c = 0; c < owner_.size(); ++c) owner_[c] = top_owner_[static_cast<std::size_t>(space.top_cell_of(static_cast<int>(c)))];
  cost_.assign(space.cells().size(), 0.0);
}

std::vector<int> RankLayout::cut_along_curve(const Space& space, const std::vector<Vec3>& centres,
                                             const std::vector<double>& counts,
                                             const std::vector<std::pair<Vec3, double>>& measured, long long steps,
                                             const std::function<std::size_t(const Vec3&)>& unit_at) {
  // The units (leaves or top cells) are ordered along a Hilbert curve through their centres,
  // so each rank's units form a compact region.
  const std::size_t nl = centres.size();
  constexpr int bits = 16;
  const double cells_per_side = static_cast<double>(1u << bits);
  // The curve runs through a cube as wide as the box's longest side, not through the box
  // stretched to a cube: in an elongated box (Sod's 4 x 1 x 1) a stretched curve may cut
  // lengthwise, giving ranks four times the common surface.
  const double side = std::max({space.box_size().x, space.box_size().y, space.box_size().z});
  std::vector<std::uint64_t> key(nl);
  for (std::size_t l = 0; l < nl; ++l) {
    const Vec3 x = centres[l];
    std::array<std::uint32_t, 3> q;
    for (int k = 0; k < 3; ++k)
      q[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(
          std::clamp((x[k] - space.box_lo()[k]) / side * cells_per_side, 0.0, cells_per_side - 1.0));
    key[l] = hilbert_key(q[0], q[1], q[2], bits);
  }
  std::vector<int> curve(nl);
  for (std::size_t l = 0; l < nl; ++l) curve[l] = static_cast<int>(l);
  std::sort(curve.begin(), curve.end(), [&](int a, int b) {
    return key[static_cast<std::size_t>(a)] != key[static_cast<std::size_t>(b)] ? key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)] : a < b;
  });
  // Work per unit: what was measured where the unit now is since the cut was made (the
  // intervals between recuts are carried over), or its particle count at first. One interval
  // is a few steps, and one task slowed by the host (a descheduled rank) could make it look
  // 30% imbalanced: a cut redone on that (Sedov 250k, 2 ranks: 6 cuts instead of 1) moved
  // the boundary off the blast's plane of symmetry and made the run ~10% slower.
  std::vector<double> work(nl, 0.0);
  if (measured.empty()) {
    work = counts;
  } else {
    std::vector<std::pair<Vec3, double>> since_cut;
    since_cut.swap(work_since_cut_);
    since_cut.insert(since_cut.end(), measured.begin(), measured.end());
    for (const auto& [x, cost] : since_cut) work[unit_at(x)] += cost;
  }
  // The cut points stay (as positions on the curve) while they still share the work well.
  const int n = ranks_;
  auto owners_from_cuts = [&] {
    std::vector<int> own(nl);
    for (std::size_t l = 0; l < nl; ++l)
      own[l] = static_cast<int>(std::upper_bound(cut_keys_.begin(), cut_keys_.end(), key[l]) - cut_keys_.begin());
    return own;
  };
  // A cut is judged only once it has stood for a span of steps. Judged on the few steps since
  // the last recut, a core slowed by the host for a while made the cut follow it (Sedov 250k,
  // 2 ranks: 12-14 cuts, each with a migration), and a cut made from the first steps' work
  // left the ranks 12% apart for the rest of the run, where the symmetric cut from particle
  // counts was even (docs/performance.md, domain.repartition_min_steps).
  std::vector<int> unit_owner;
  if (cut_keys_.size() == static_cast<std::size_t>(n - 1)) {
    unit_owner = owners_from_cuts();
    const bool judged = steps - cut_step_ >= min_steps_;
    if (judged && needs_repartition(imbalance(work, unit_owner, n), imbalance_))
      unit_owner.clear();
  }
  if (unit_owner.empty()) {
    const std::vector<int> cut = partition(curve, work, n);
    // Rank r starts at the first unit along the curve that the cut gives to r or beyond.
    cut_keys_.assign(static_cast<std::size_t>(n - 1), std::numeric_limits<std::uint64_t>::max());
    for (int l : curve)
      for (int r = 1; r <= cut[static_cast<std::size_t>(l)]; ++r)
        cut_keys_[static_cast<std::size_t>(r - 1)] = std::min(cut_keys_[static_cast<std::size_t>(r - 1)], key[static_cast<std::size_t>(l)]);
    unit_owner = owners_from_cuts();
    ++partitions_;
    cut_step_ = steps;
  } else if (!measured.empty()) {
    work_since_cut_.clear();
    for (std::size_t l = 0; l < nl; ++l)
      if (work[l] > 0.0) work_since_cut_.push_back({centres[l], work[l]});
  }
  return unit_owner;
}

}  // namespace fountain::domain
