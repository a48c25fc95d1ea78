#include "groups/Hop.hpp"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

#include "core/Error.hpp"
#include "groups/NearestNeighbours.hpp"

namespace fountain::groups {

namespace {

// The M4 spline with support 2h, normalised to unit integral (HOP's kernel).
double spline(double r, double h) {
  const double q = r / h;
  const double norm = 1.0 / (std::numbers::pi * h * h * h);
  if (q < 1.0) return norm * (1.0 - 1.5 * q * q + 0.75 * q * q * q);
  if (q < 2.0) return norm * 0.25 * (2.0 - q) * (2.0 - q) * (2.0 - q);
  return 0.0;
}

// Each particle's k nearest (itself among them), nearest first: row i of a k-column table.
struct NeighbourTable {
  std::size_t k = 0;
  std::vector<std::uint32_t> index;
  std::vector<double> h;  // half the distance to the k-th
  const std::uint32_t* row(std::size_t i) const { return index.data() + i * k; }
};

NeighbourTable neighbour_table(const NearestNeighbours& tree, std::span<const Vec3> x, std::size_t k) {
  NeighbourTable t;
  t.k = std::min(k, x.size());
  t.index.resize(x.size() * t.k);
  t.h.resize(x.size());
  // In the tree's order: neighbouring queries share the nodes they visit.
  const std::vector<std::uint32_t>& order = tree.order();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<NearestNeighbours::Neighbour> found;
    NearestNeighbours::SearchStack stack;
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const std::size_t i = order[p];
      tree.nearest(x[i], t.k, found, stack);
      for (std::size_t n = 0; n < t.k; ++n) t.index[i * t.k + n] = found[n].index;
      t.h[i] = 0.5 * std::sqrt(found.back().distance2);
    }
  });
  return t;
}

std::vector<double> densities(const NearestNeighbours& tree, const NeighbourTable& t, std::span<const Vec3> x,
                              std::span<const double> mass) {
  const std::size_t n = x.size();
  std::vector<double> rho(n, 0.0);
  // Gather: each particle's own smoothing over its list.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t* row = t.row(i);
      double sum = 0.0;
      for (std::size_t k = 0; k < t.k; ++k) sum += 0.5 * mass[row[k]] * spline(norm(tree.separation(x[i], x[row[k]])), t.h[i]);
      rho[i] = sum;
    }
  });
  // Scatter: W(r_ij, h_j) is non-zero only for i in j's list, so each list hands its own
  // smoothing out. In index order, serially: the sums are the same on any thread count.
  std::vector<double> scatter(n, 0.0);
  for (std::size_t j = 0; j < n; ++j) {
    const std::uint32_t* row = t.row(j);
    for (std::size_t k = 0; k < t.k; ++k)
      scatter[row[k]] += 0.5 * mass[j] * spline(norm(tree.separation(x[j], x[row[k]])), t.h[j]);
  }
  for (std::size_t i = 0; i < n; ++i) rho[i] += scatter[i];
  return rho;
}

// Union-find on group indices that keeps the lower index as the root.
struct LowerRoot {
  std::vector<std::size_t> parent;
  explicit LowerRoot(std::size_t n) : parent(n) {
    for (std::size_t i = 0; i < n; ++i) parent[i] = i;
  }
  std::size_t find(std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

std::vector<double> hop_densities(std::span<const Vec3> x, std::span<const double> mass, int n_dens, double box) {
  if (n_dens < 2) throw InputError("HOP's density needs at least 2 neighbours");
  const NearestNeighbours tree(x, box);
  return densities(tree, neighbour_table(tree, x, static_cast<std::size_t>(n_dens)), x, mass);
}

HopResult find_hop_groups(std::span<const Vec3> x, std::span<const double> mass, const HopParameters& p) {
  if (!(p.n_merge < p.n_hop && p.n_hop <= p.n_dens && p.n_merge >= 1))
    throw InputError(fmt::format("HOP needs 1 <= N_merge < N_hop <= N_dens; they are {}, {} and {}", p.n_merge, p.n_hop, p.n_dens));
  if (!(p.delta_outer > 0.0 && p.delta_saddle >= p.delta_outer && p.delta_peak >= p.delta_saddle))
    throw InputError("HOP needs 0 < delta_outer <= delta_saddle <= delta_peak");
  const std::size_t n = x.size();
  HopResult out;
  out.group.assign(n, -1);
  if (n == 0) return out;
  const NearestNeighbours tree(x, p.box);
  const NeighbourTable t = neighbour_table(tree, x, static_cast<std::size_t>(p.n_dens));
  out.density = densities(tree, t, x, mass);
  const std::vector<double>& rho = out.density;
  // Denser first; equal densities by the lower index: a strict order, so hops never cycle.
  auto denser = [&](std::uint32_t a, std::uint32_t b) { return rho[a] > rho[b] || (rho[a] == rho[b] && a < b); };

  // Hops: each particle to the densest of its n_hop nearest, then along the chain to a peak.
  const std::size_t n_hop = std::min<std::size_t>(static_cast<std::size_t>(p.n_hop), t.k);
  std::vector<std::uint32_t> next(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t best = static_cast<std::uint32_t>(i);
    for (std::size_t k = 0; k < n_hop; ++k)
      if (denser(t.row(i)[k], best)) best = t.row(i)[k];
    next[i] = best;
  }
  std::vector<std::uint32_t> peak(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t j = static_cast<std::uint32_t>(i);
    while (next[j] != j) j = next[j];
    peak[i] = j;
  }
  // Groups numbered by their peaks in index order.
  std::vector<std::int64_t> number(n, -1);
  std::vector<std::uint32_t> peaks;
  for (std::size_t i = 0; i < n; ++i)
    if (peak[i] == i) number[i] = static_cast<std::int64_t>(peaks.size()), peaks.push_back(static_cast<std::uint32_t>(i));
  const std::size_t groups = peaks.size();
  auto group_of = [&](std::size_t i) { return static_cast<std::size_t>(number[peak[i]]); };

  // Boundaries: the densest mean density of a pair of neighbours (the n_merge nearest, not
  // itself) across two groups.
  std::map<std::pair<std::size_t, std::size_t>, double> boundary;
  for (std::size_t i = 0; i < n; ++i) {
    int taken = 0;
    for (std::size_t k = 0; k < t.k && taken < p.n_merge; ++k) {
      const std::uint32_t j = t.row(i)[k];
      if (j == i) continue;
      ++taken;
      const std::size_t a = group_of(i), b = group_of(j);
      if (a == b) continue;
      double& edge = boundary[{std::min(a, b), std::max(a, b)}];
      edge = std::max(edge, 0.5 * (rho[i] + rho[j]));
    }
  }

  // Regroup. Viable groups (peak >= delta_peak) merge through saddles >= delta_saddle.
  std::vector<bool> viable(groups);
  for (std::size_t g = 0; g < groups; ++g) viable[g] = rho[peaks[g]] >= p.delta_peak;
  LowerRoot merged(groups);
  for (const auto& [pair, b] : boundary)
    if (viable[pair.first] && viable[pair.second] && b >= p.delta_saddle) merged.unite(pair.first, pair.second);
  // A non-viable group records its highest boundary to a viable one, and passes it on through
  // boundaries above delta_outer to other non-viable groups (capped by those boundaries).
  const double none = -std::numeric_limits<double>::infinity();
  std::vector<double> record(groups, none);
  std::vector<std::int64_t> target(groups, -1);
  auto offer = [&](std::size_t g, double b, std::int64_t to) {
    if (b > record[g] || (b == record[g] && to >= 0 && (target[g] < 0 || to < target[g]))) {
      record[g] = b, target[g] = to;
      return true;
    }
    return false;
  };
  for (const auto& [pair, b] : boundary) {
    const auto [g1, g2] = pair;
    if (viable[g1] != viable[g2]) {
      const std::size_t v = viable[g1] ? g1 : g2, w = viable[g1] ? g2 : g1;
      offer(w, b, static_cast<std::int64_t>(merged.find(v)));
    }
  }
  for (bool changed = true; changed;) {
    changed = false;
    for (const auto& [pair, b] : boundary) {
      const auto [g1, g2] = pair;
      if (viable[g1] || viable[g2] || !(b > p.delta_outer) || !(rho[peaks[g1]] > p.delta_outer) ||
          !(rho[peaks[g2]] > p.delta_outer))
        continue;
      if (target[g1] >= 0) changed = offer(g2, std::min(b, record[g1]), target[g1]) || changed;
      if (target[g2] >= 0) changed = offer(g1, std::min(b, record[g2]), target[g2]) || changed;
    }
  }
  std::vector<std::int64_t> final_group(groups, -1);
  for (std::size_t g = 0; g < groups; ++g) {
    if (viable[g]) final_group[g] = static_cast<std::int64_t>(merged.find(g));
    else if (target[g] >= 0 && record[g] >= p.delta_outer) final_group[g] = target[g];
  }

  // Members: particles at or above delta_outer; groups of fewer than min_members dropped.
  std::vector<HopGroup> by_final(groups);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(rho[i] >= p.delta_outer)) continue;
    const std::int64_t g = final_group[group_of(i)];
    if (g < 0) continue;
    HopGroup& hg = by_final[static_cast<std::size_t>(g)];
    hg.members.push_back(static_cast<std::uint32_t>(i));
    hg.mass += mass[i];
    if (hg.members.size() == 1 || denser(static_cast<std::uint32_t>(i), hg.peak)) hg.peak = static_cast<std::uint32_t>(i);
  }
  std::vector<std::size_t> kept;
  for (std::size_t g = 0; g < groups; ++g)
    if (by_final[g].members.size() >= p.min_members) kept.push_back(g);
  std::stable_sort(kept.begin(), kept.end(),
                   [&](std::size_t a, std::size_t b) { return by_final[a].members.size() > by_final[b].members.size(); });
  for (std::size_t g : kept) {
    HopGroup hg = std::move(by_final[g]);
    hg.peak_density = rho[hg.peak];
    for (std::uint32_t i : hg.members) out.group[i] = static_cast<std::int64_t>(out.groups.size());
    out.groups.push_back(std::move(hg));
  }
  return out;
}

}  // namespace fountain::groups
