#include "groups/HopAcrossRanks.hpp"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"
#include "groups/NearestNeighbours.hpp"
#include "groups/SlabsAcrossRanks.hpp"

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

// One particle on its way between ranks.
struct Particle {
  Vec3 x, v;
  double m = 0.0, hop_m = 0.0;  // its own mass; with its hidden stars
  std::uint64_t id = 0, origin = 0;
  std::int32_t type = 0, pad = 0;
};

// A share of a particle's density that its neighbour's rank found: W(r_ij, h_j) m_j / 2 for i.
struct Scatter {
  std::uint64_t target = 0, source = 0;
  double value = 0.0;
};

// Where a hop chain leaves the particles of a rank: at a peak, or at a copy of another's.
struct ChainEnd {
  std::uint64_t id = 0;   // the particle
  std::uint64_t end = 0;  // its peak, or the copy its chain hops to
  std::int32_t leaves = 0, pad = 0;
};

struct PeakDensity {
  std::uint64_t id = 0;
  double rho = 0.0;
};

struct Edge {
  std::uint64_t a = 0, b = 0;  // group numbers, a < b
  double density = 0.0;
};

// A member on its way to its group's home.
struct Member {
  std::uint64_t group = 0;  // the final group's number
  double rho = 0.0;
  Particle p;
};

// A group as its home found it, for rank 0.
struct Summary {
  double mass = 0.0, peak_density = 0.0;
  std::array<double, 6> mass_by_type{};
  std::array<std::uint64_t, 6> count_by_type{};
  Vec3 peak, centre_of_mass, velocity;
  std::uint64_t number = 0, members = 0, peak_member = 0;
};

struct MemberName {
  std::uint64_t id = 0, origin = 0;
  double rho = 0.0;
  std::int32_t type = 0, pad = 0;
};

// Union-find on group numbers that keeps the lower number as the root.
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

// HOP's regroup (docs/groups.md): each group's final group (-1: dropped), from the peaks'
// densities and the boundaries between groups.
std::vector<std::int64_t> regroup(const std::vector<double>& peak_rho, const std::map<std::pair<std::size_t, std::size_t>, double>& boundary,
                                  const HopParameters& p) {
  const std::size_t groups = peak_rho.size();
  std::vector<bool> viable(groups);
  for (std::size_t g = 0; g < groups; ++g) viable[g] = peak_rho[g] >= p.delta_peak;
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
      if (viable[g1] || viable[g2] || !(b > p.delta_outer) || !(peak_rho[g1] > p.delta_outer) || !(peak_rho[g2] > p.delta_outer))
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
  return final_group;
}

}  // namespace

HopCatalogue find_hop_groups_across_ranks(const ParticleSet& mine, std::span<const double> hidden, const HopParameters& p,
                                          Collectives* ranks) {
  if (p.n_dens < 2) throw InputError("HOP's density needs at least 2 neighbours");
  if (!(p.n_merge < p.n_hop && p.n_hop <= p.n_dens && p.n_merge >= 1))
    throw InputError(fmt::format("HOP needs 1 <= N_merge < N_hop <= N_dens; they are {}, {} and {}", p.n_merge, p.n_hop, p.n_dens));
  if (!(p.delta_outer > 0.0 && p.delta_saddle >= p.delta_outer && p.delta_peak >= p.delta_saddle))
    throw InputError("HOP needs 0 < delta_outer <= delta_saddle <= delta_peak");
  if (hidden.size() != mine.size()) throw std::invalid_argument("HOP: one hidden mass per particle");
  const int count = ranks == nullptr ? 1 : ranks->size(), me = ranks == nullptr ? 0 : ranks->rank();
  const double box = p.box;

  // Each particle to the owner of its slab; a slab's particles by ID.
  std::vector<Particle> own(mine.size());
  for (std::size_t i = 0; i < mine.size(); ++i) {
    const Vec3 x = box > 0.0 ? wrap_into_box(mine.x[i], Vec3{box, box, box}) : mine.x[i];
    own[i] = {x, mine.v[i], mine.mass[i], mine.mass[i] + hidden[i], mine.id[i], static_cast<std::uint64_t>(i), mine.type[i], 0};
  }
  const Slabs slabs = into_slabs(own, box, ranks);
  const std::size_t n_own = own.size();
  const std::uint64_t total = count_over_ranks(n_own, ranks);
  HopCatalogue out;
  if (total == 0) return out;
  const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(p.n_dens), total);

  // The particles this rank reads: its own and copies of others' within `margin` of its slab,
  // by ID. The margin starts at three mean spacings and widens to what the particles whose
  // neighbours reached beyond it need: their k-th neighbour found among too few particles is
  // no nearer than the true one, so the next margin suffices for them. A particle's list, once
  // found inside the margin, holds; the next attempt moves it to the wider set's places.
  std::vector<Particle> copies;
  std::vector<int> copy_from;                     // each copy's rank
  std::vector<std::vector<std::uint32_t>> sent;   // own particles copied to each rank
  std::vector<std::uint32_t> local;               // own (index < n_own) and copies (n_own + index), by ID
  std::vector<Vec3> xs;
  std::vector<std::uint32_t> row(n_own * k, 0);   // each own particle's k nearest, as places in `local`
  std::vector<double> h(n_own);
  std::vector<std::uint32_t> place_of_own(n_own);  // own particle's place in `local`
  std::vector<char> listed(n_own, 0);              // its list is found and complete
  std::vector<std::uint64_t> listed_ids;           // the last attempt's `local`, as IDs
  auto particle = [&](std::uint32_t at) -> const Particle& { return at < n_own ? own[at] : copies[at - n_own]; };
  double margin = 3.0 * slabs.extent() / std::cbrt(static_cast<double>(total));
  for (int attempt = 0;; ++attempt) {
    copies.clear(), copy_from.clear();
    sent.assign(static_cast<std::size_t>(count), {});
    if (ranks != nullptr) {
      std::vector<std::vector<Particle>> to(static_cast<std::size_t>(count));
      for (std::size_t i = 0; i < n_own; ++i)
        for (int q = 0; q < count; ++q)
          if (q != me && slabs.near(own[i].x.x, q, margin)) {
            to[static_cast<std::size_t>(q)].push_back(own[i]);
            sent[static_cast<std::size_t>(q)].push_back(static_cast<std::uint32_t>(i));
          }
      // The copies arrive in rank order: note each one's rank from the counts sent.
      std::vector<std::uint64_t> sizes_to(static_cast<std::size_t>(count));
      for (int q = 0; q < count; ++q) sizes_to[static_cast<std::size_t>(q)] = to[static_cast<std::size_t>(q)].size();
      const std::vector<std::uint64_t> all_sizes = gather_all(sizes_to, ranks);
      copies = exchange(to, ranks);
      for (int q = 0; q < count; ++q)
        if (q != me) copy_from.insert(copy_from.end(), all_sizes[static_cast<std::size_t>(q * count + me)], q);
      if (copy_from.size() != copies.size()) throw std::logic_error("HOP: copies and their ranks disagree");
    }
    // Own particles are in ID order already: the copies sorted, then the two merged.
    std::vector<std::uint32_t> by_id(copies.size());
    for (std::size_t c = 0; c < copies.size(); ++c) by_id[c] = static_cast<std::uint32_t>(n_own + c);
    auto before = [&](std::uint32_t a, std::uint32_t b) {
      return std::tie(particle(a).id, particle(a).origin) < std::tie(particle(b).id, particle(b).origin);
    };
    std::sort(by_id.begin(), by_id.end(), before);
    local.resize(n_own + copies.size());
    {
      std::size_t i = 0, c = 0, t = 0;
      while (i < n_own || c < by_id.size())
        local[t++] = c == by_id.size() || (i < n_own && before(static_cast<std::uint32_t>(i), by_id[c])) ? static_cast<std::uint32_t>(i++)
                                                                                                       : by_id[c++];
    }
    xs.resize(local.size());
    for (std::size_t t = 0; t < local.size(); ++t) {
      xs[t] = particle(local[t]).x;
      if (local[t] < n_own) place_of_own[local[t]] = static_cast<std::uint32_t>(t);
    }
    if (attempt > 0) {
      // The wider set holds the narrower one: both by ID, so one pass finds the new places.
      std::vector<std::uint32_t> moved(listed_ids.size());
      for (std::size_t o = 0, t = 0; o < listed_ids.size(); ++o) {
        while (particle(local[t]).id != listed_ids[o]) ++t;
        moved[o] = static_cast<std::uint32_t>(t);
      }
      for (std::size_t i = 0; i < n_own; ++i)
        if (listed[i])
          for (std::size_t n = 0; n < k; ++n) row[i * k + n] = moved[row[i * k + n]];
    }
    listed_ids.resize(local.size());
    for (std::size_t t = 0; t < local.size(); ++t) listed_ids[t] = particle(local[t]).id;
    const bool short_of = n_own > 0 && local.size() < k;  // a rank with no particles needs no list
    double needed = 0.0;
    if (!short_of) {
      // In the tree's order: neighbouring queries share the nodes they visit.
      const NearestNeighbours tree(xs, box);
      const std::vector<std::uint32_t>& order = tree.order();
      std::vector<double> reach(n_own, 0.0);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<NearestNeighbours::Neighbour> found;
        NearestNeighbours::SearchStack stack;
        for (std::size_t at = r.begin(); at != r.end(); ++at) {
          const std::uint32_t i = local[order[at]];
          if (i >= n_own || listed[i]) continue;
          tree.nearest(own[i].x, k, found, stack);
          for (std::size_t n = 0; n < k; ++n) row[i * k + n] = found[n].index;
          const double r_k = std::sqrt(found.back().distance2);
          h[i] = 0.5 * r_k;
          reach[i] = ranks == nullptr || count == 1 ? 0.0 : r_k - slabs.depth(own[i].x.x, me);
          listed[i] = reach[i] < margin * (1.0 - 1e-9);
        }
      });
      for (std::size_t i = 0; i < n_own; ++i)
        if (!listed[i]) needed = std::max(needed, reach[i]);
    }
    // Complete where every own particle's ball of its k nearest lies inside the margin.
    const bool complete = !short_of && std::all_of(listed.begin(), listed.end(), [](char c) { return c != 0; });
    std::vector<double> asks{complete ? 0.0 : (short_of ? 2.0 * margin : std::max(1.1 * margin, 1.01 * needed))};
    if (ranks != nullptr) asks = gather_all(asks, ranks);
    const double widest = *std::max_element(asks.begin(), asks.end());
    if (widest == 0.0) break;
    if (ranks == nullptr || attempt > 64) throw std::logic_error("HOP: the margins did not converge");
    margin = widest;
  }
  std::vector<std::uint64_t>().swap(listed_ids);
  std::vector<char>().swap(listed);
  std::vector<double> ms(local.size());  // HOP masses by place
  for (std::size_t t = 0; t < local.size(); ++t) ms[t] = particle(local[t]).hop_m;
  const NearestNeighbours tree(xs, box);

  // Densities: each particle's own smoothing over its list, then what each list hands out
  // (W(r_ij, h_j) is non-zero only for i in j's list). A particle's scattered shares are summed
  // in increasing ID of their sources, as one process sums them: those from other ranks, and
  // this rank's for the same particles, are sorted first.
  std::vector<double> rho(n_own, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_own, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t* list = &row[i * k];
      double sum = 0.0;
      for (std::size_t n = 0; n < k; ++n)
        sum += 0.5 * ms[list[n]] * spline(norm(tree.separation(own[i].x, xs[list[n]])), h[i]);
      rho[i] = sum;
    }
  });
  std::vector<Scatter> from_others;
  if (ranks != nullptr) {
    std::vector<std::vector<Scatter>> to(static_cast<std::size_t>(count));
    for (std::size_t j = 0; j < n_own; ++j)
      for (std::size_t n = 0; n < k; ++n) {
        const std::uint32_t t = local[row[j * k + n]];
        if (t < n_own) continue;
        const double value = 0.5 * own[j].hop_m * spline(norm(tree.separation(own[j].x, xs[row[j * k + n]])), h[j]);
        to[static_cast<std::size_t>(copy_from[t - n_own])].push_back({copies[t - n_own].id, own[j].id, value});
      }
    from_others = exchange(to, ranks);
  }
  std::vector<char> mixed(n_own, 0);  // gets shares from other ranks
  auto own_index = [&](std::uint64_t id) {
    const auto it = std::lower_bound(own.begin(), own.end(), id, [](const Particle& a, std::uint64_t v) { return a.id < v; });
    if (it == own.end() || it->id != id) throw std::logic_error("HOP: a share for a particle this rank does not own");
    return static_cast<std::size_t>(it - own.begin());
  };
  std::vector<std::pair<std::size_t, Scatter>> shares;
  for (const Scatter& s : from_others) {
    const std::size_t i = own_index(s.target);
    mixed[i] = 1;
    shares.push_back({i, s});
  }
  std::vector<double> scatter(n_own, 0.0);
  for (std::size_t j = 0; j < n_own; ++j)
    for (std::size_t n = 0; n < k; ++n) {
      const std::uint32_t t = local[row[j * k + n]];
      if (t >= n_own) continue;
      const double value = 0.5 * own[j].hop_m * spline(norm(tree.separation(own[j].x, xs[row[j * k + n]])), h[j]);
      if (mixed[t]) shares.push_back({t, {own[t].id, own[j].id, value}});
      else scatter[t] += value;
    }
  std::sort(shares.begin(), shares.end(), [](const auto& a, const auto& b) { return std::tie(a.first, a.second.source) < std::tie(b.first, b.second.source); });
  for (const auto& [i, s] : shares) scatter[i] += s.value;
  for (std::size_t i = 0; i < n_own; ++i) rho[i] += scatter[i];
  std::vector<double>().swap(scatter);
  std::vector<std::pair<std::size_t, Scatter>>().swap(shares);

  // The copies' densities, from their owners in the order they were sent.
  std::vector<double> copy_rho;
  if (ranks != nullptr) {
    std::vector<std::vector<double>> to(static_cast<std::size_t>(count));
    for (int q = 0; q < count; ++q)
      for (std::uint32_t i : sent[static_cast<std::size_t>(q)]) to[static_cast<std::size_t>(q)].push_back(rho[i]);
    copy_rho = exchange(to, ranks);
  }
  auto rho_at = [&](std::uint32_t place) { const std::uint32_t t = local[place]; return t < n_own ? rho[t] : copy_rho[t - n_own]; };
  auto id_at = [&](std::uint32_t place) { return particle(local[place]).id; };
  // Denser first; equal densities by the lower ID: a strict order, so hops never cycle.
  auto denser = [&](std::uint32_t a, std::uint32_t b) {
    const double ra = rho_at(a), rb = rho_at(b);
    return ra > rb || (ra == rb && id_at(a) < id_at(b));
  };

  // Hops: each particle to the densest of its n_hop nearest; chains followed on this rank to
  // a peak or to a copy, and through the other ranks' chain ends from there.
  const std::size_t n_hop = std::min<std::size_t>(static_cast<std::size_t>(p.n_hop), k);
  std::vector<std::uint32_t> next(n_own);
  for (std::size_t i = 0; i < n_own; ++i) {
    std::uint32_t best = place_of_own[i];
    for (std::size_t n = 0; n < n_hop; ++n)
      if (denser(row[i * k + n], best)) best = row[i * k + n];
    next[i] = best;
  }
  std::vector<ChainEnd> end(n_own);
  {
    std::vector<char> known(n_own, 0);
    std::vector<std::size_t> path;
    for (std::size_t i = 0; i < n_own; ++i) {
      std::size_t j = i;
      path.clear();
      ChainEnd e;
      for (;;) {
        if (known[j]) {
          e = end[j];
          break;
        }
        path.push_back(j);
        const std::uint32_t t = local[next[j]];
        if (next[j] == place_of_own[j]) {
          e = {0, own[j].id, 0, 0};
          break;
        }
        if (t >= n_own) {
          e = {0, copies[t - n_own].id, 1, 0};
          break;
        }
        j = t;
      }
      for (std::size_t q : path) end[q] = {own[q].id, e.end, e.leaves, 0}, known[q] = 1;
    }
  }
  std::unordered_map<std::uint64_t, std::pair<std::uint64_t, bool>> ends;  // copied particle: its chain's end here
  if (ranks != nullptr) {
    std::vector<ChainEnd> mine_copied;
    std::vector<char> copied(n_own, 0);
    for (const auto& list : sent)
      for (std::uint32_t i : list) copied[i] = 1;
    for (std::size_t i = 0; i < n_own; ++i)
      if (copied[i]) mine_copied.push_back(end[i]);
    for (const ChainEnd& e : gather_all(mine_copied, ranks)) ends[e.id] = {e.end, e.leaves != 0};
  }
  auto peak_of = [&](std::uint64_t id, bool leaves) {
    while (leaves) {
      const auto it = ends.find(id);
      if (it == ends.end()) throw std::logic_error("HOP: a chain hops to a particle no rank copied");
      std::tie(id, leaves) = it->second;
    }
    return id;
  };
  std::vector<std::uint64_t> peak(n_own);
  for (std::size_t i = 0; i < n_own; ++i) peak[i] = peak_of(end[i].end, end[i].leaves != 0);
  std::vector<ChainEnd>().swap(end);

  // Groups numbered by their peaks' IDs.
  std::vector<PeakDensity> peaks;
  for (std::size_t i = 0; i < n_own; ++i)
    if (peak[i] == own[i].id) peaks.push_back({own[i].id, rho[i]});
  peaks = gather_all(peaks, ranks);
  std::sort(peaks.begin(), peaks.end(), [](const PeakDensity& a, const PeakDensity& b) { return a.id < b.id; });
  std::unordered_map<std::uint64_t, std::size_t> number;
  number.reserve(peaks.size());
  for (std::size_t g = 0; g < peaks.size(); ++g) number[peaks[g].id] = g;

  // Boundaries: the densest mean density of a pair of neighbours (the n_merge nearest, not
  // itself) across two groups, over every rank.
  std::map<std::pair<std::size_t, std::size_t>, double> boundary;
  {
    std::vector<std::size_t> group_of(local.size());  // by place
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, local.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t place = r.begin(); place != r.end(); ++place) {
        const std::uint32_t t = local[place];
        group_of[place] = number.at(t < n_own ? peak[t] : peak_of(copies[t - n_own].id, true));
      }
    });
    auto group_of_place = [&](std::uint32_t place) { return group_of[place]; };
    for (std::size_t i = 0; i < n_own; ++i) {
      int taken = 0;
      const std::size_t a = group_of[place_of_own[i]];
      for (std::size_t n = 0; n < k && taken < p.n_merge; ++n) {
        const std::uint32_t j = row[i * k + n];
        if (j == place_of_own[i]) continue;
        ++taken;
        const std::size_t b = group_of_place(j);
        if (a == b) continue;
        double& edge = boundary[{std::min(a, b), std::max(a, b)}];
        edge = std::max(edge, 0.5 * (rho[i] + rho_at(j)));
      }
    }
    if (ranks != nullptr) {
      std::vector<Edge> edges;
      for (const auto& [pair, b] : boundary) edges.push_back({pair.first, pair.second, b});
      for (const Edge& e : gather_all(edges, ranks)) {
        double& edge = boundary[{e.a, e.b}];
        edge = std::max(edge, e.density);
      }
    }
  }
  std::vector<double> peak_rho(peaks.size());
  for (std::size_t g = 0; g < peaks.size(); ++g) peak_rho[g] = peaks[g].rho;
  const std::vector<std::int64_t> final_group = regroup(peak_rho, boundary, p);

  // Members (at or above delta_outer) to their group's home; each home's groups found there.
  std::vector<Member> members;
  {
    std::vector<std::vector<Member>> to(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < n_own; ++i) {
      if (!(rho[i] >= p.delta_outer)) continue;
      const std::int64_t g = final_group[number.at(peak[i])];
      if (g < 0) continue;
      to[static_cast<std::size_t>(g % count)].push_back({static_cast<std::uint64_t>(g), rho[i], own[i]});
    }
    members = exchange(to, ranks);
  }
  std::sort(members.begin(), members.end(),
            [](const Member& a, const Member& b) { return std::tie(a.group, a.p.id, a.p.origin) < std::tie(b.group, b.p.id, b.p.origin); });
  std::vector<std::size_t> first;
  for (std::size_t m = 0; m < members.size(); ++m)
    if (m == 0 || members[m].group != members[m - 1].group) first.push_back(m);
  const std::size_t homed = first.size();
  first.push_back(members.size());
  std::vector<Summary> summary(homed);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, homed, 1), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      Summary& s = summary[g];
      const std::size_t b = first[g], e = first[g + 1];
      s.number = members[b].group;
      s.members = e - b;
      std::size_t top = b;  // the densest; equal densities to the lower ID
      for (std::size_t m = b; m < e; ++m) {
        s.mass += members[m].p.hop_m;
        if (members[m].rho > members[top].rho) top = m;
      }
      s.peak_member = top - b;
      s.peak = members[top].p.x;
      s.peak_density = members[top].rho;
      Vec3 moment{}, momentum{};
      for (std::size_t m = b; m < e; ++m) {
        const Particle& q = members[m].p;
        const auto t = static_cast<std::size_t>(std::clamp(q.type, 0, 5));
        ++s.count_by_type[t];
        // Gas carries its hidden stars: its own mass under type 0, the hidden part under type 4.
        s.mass_by_type[t] += q.m;
        if (q.hop_m > q.m) s.mass_by_type[4] += q.hop_m - q.m;
        Vec3 d = q.x - s.peak;
        if (box > 0.0)
          for (int c = 0; c < 3; ++c) d[c] -= box * std::nearbyint(d[c] / box);
        moment += d * q.hop_m;
        momentum += q.v * q.hop_m;
      }
      Vec3 c = s.peak + moment * (1.0 / s.mass);
      if (box > 0.0)
        for (int a = 0; a < 3; ++a) c[a] -= box * std::floor(c[a] / box);
      s.centre_of_mass = c;
      s.velocity = momentum * (1.0 / s.mass);
    }
  });

  // Every particle's density, when alone.
  if (ranks == nullptr) {
    out.density.resize(n_own);
    for (std::size_t i = 0; i < n_own; ++i) out.density[own[i].origin] = rho[i];
  }

  // The catalogue on rank 0: groups of at least min_members, largest first, ties by number.
  std::vector<Summary> kept;
  std::vector<MemberName> names;
  for (std::size_t g = 0; g < homed; ++g) {
    if (summary[g].members < p.min_members) continue;
    kept.push_back(summary[g]);
    for (std::size_t m = first[g]; m < first[g + 1]; ++m)
      names.push_back({members[m].p.id, members[m].p.origin, members[m].rho, members[m].p.type, 0});
  }
  std::vector<Member>().swap(members);
  kept = on_rank_zero(std::move(kept), ranks);
  names = on_rank_zero(std::move(names), ranks);
  if (me != 0) return out;
  std::vector<std::size_t> start(kept.size() + 1, 0);
  for (std::size_t g = 0; g < kept.size(); ++g) start[g + 1] = start[g] + kept[g].members;
  if (start.back() != names.size()) throw std::logic_error("HOP: members and groups disagree");
  std::vector<std::size_t> order(kept.size());
  for (std::size_t g = 0; g < order.size(); ++g) order[g] = g;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (kept[a].members != kept[b].members) return kept[a].members > kept[b].members;
    return kept[a].number < kept[b].number;
  });
  for (std::size_t g : order) {
    const Summary& s = kept[g];
    HopCatalogueGroup c;
    c.mass = s.mass;
    c.mass_by_type = s.mass_by_type;
    c.count_by_type = s.count_by_type;
    c.peak_density = s.peak_density;
    c.peak = s.peak;
    c.centre_of_mass = s.centre_of_mass;
    c.velocity = s.velocity;
    c.peak_member = out.member_id.size() + s.peak_member;
    for (std::size_t m = start[g]; m < start[g + 1]; ++m) {
      c.members.push_back(static_cast<std::uint32_t>(out.member_id.size()));
      out.member_id.push_back(names[m].id);
      out.member_origin.push_back(names[m].origin);
      out.member_type.push_back(names[m].type);
      out.member_density.push_back(names[m].rho);
    }
    out.groups.push_back(std::move(c));
  }
  return out;
}

}  // namespace fountain::groups
