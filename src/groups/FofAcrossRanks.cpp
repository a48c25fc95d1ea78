#include "groups/FofAcrossRanks.hpp"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "core/Error.hpp"
#include "core/ExactSum.hpp"
#include "core/PeriodicWrap.hpp"
#include "gravity/GravityTree.hpp"
#include "groups/FriendsOfFriends.hpp"
#include "groups/SlabsAcrossRanks.hpp"

namespace fountain::groups {

namespace {

// One particle on its way between ranks; `origin` is its index in its first rank's set.
struct Record {
  Vec3 x, v;
  double m = 0.0;
  std::uint64_t id = 0, origin = 0;
  std::int32_t type = 0, pad = 0;
};

Vec3 folded(const Vec3& x, double box) { return box > 0.0 ? wrap_into_box(x, Vec3{box, box, box}) : x; }

// Union-find over particle IDs: a set's root is its smallest ID, whatever the order of the unions.
class IdUnion {
 public:
  std::uint64_t find(std::uint64_t a) {
    std::uint64_t r = a;
    for (auto it = parent_.find(r); it != parent_.end() && it->second != r; it = parent_.find(r)) r = it->second;
    while (a != r) {  // path compression
      auto it = parent_.find(a);
      a = std::exchange(it->second, r);
    }
    return r;
  }
  void unite(std::uint64_t a, std::uint64_t b) {
    a = find(a), b = find(b);
    if (a > b) std::swap(a, b);
    parent_.try_emplace(a, a);
    if (b != a) parent_[b] = a;
  }
  bool contains(std::uint64_t a) const { return parent_.count(a) != 0; }

 private:
  std::unordered_map<std::uint64_t, std::uint64_t> parent_;
};

// The member of least potential (ties: the first), from the group's own gravity.
std::size_t potential_minimum(const std::vector<Vec3>& local, const std::vector<double>& mass, double softening, double G) {
  if (local.size() == 1) return 0;
  const std::vector<double> soft(local.size(), softening);
  const gravity::GravityTree tree(local, mass, soft);
  std::vector<gravity::GravityTarget> targets(local.size());
  for (std::size_t k = 0; k < local.size(); ++k)
    targets[k] = {local[k], softening, gravity::kNoOldAcceleration, static_cast<std::int64_t>(k)};
  std::vector<gravity::GravityResult> results(local.size());
  gravity::WalkConfig walk;
  walk.G = G;
  walk.theta = 0.5;
  tree.accelerate(targets, walk, results);
  std::size_t best = 0;
  for (std::size_t k = 1; k < local.size(); ++k)
    if (results[k].potential < results[best].potential) best = k;
  return best;
}

// A group's members (by type, then ID), with what the catalogue needs of them.
struct Member {
  std::uint64_t group = 0;  // its smallest primary ID
  Record r;
};

// A member where its group is homed: its group, and its place among the home's own particles
// (at < own.size()) or, after them, among the guests other ranks sent.
struct MemberRef {
  std::uint64_t group = 0;
  std::size_t at = 0;
};

// A group as found on its home rank, for rank 0.
struct GroupSummary {
  double mass = 0.0;
  std::array<double, 6> mass_by_type{};
  std::array<std::uint64_t, 6> count_by_type{};
  Vec3 centre_of_mass, potential_minimum, velocity;
  double m200 = 0.0, r200 = 0.0;
  std::uint64_t smallest_id = 0, members = 0;
};

struct MemberName {
  std::uint64_t id = 0, origin = 0;
  std::int32_t type = 0, pad = 0;
};

// A spherical overdensity's question to every rank: its particles within `radius` of `centre`.
struct ShellQuery {
  Vec3 centre;
  double radius = 0.0;
  std::uint64_t slot = 0;  // the group's place on its home rank
  std::int32_t home = 0, pad = 0;
};
struct ShellAnswer {
  std::uint64_t slot = 0;
  double r = 0.0, m = 0.0;
};

}  // namespace

double sum_in_any_order(const std::vector<double>& mine, Collectives* ranks) {
  ExactSum sum;
  for (double v : mine) sum.add(v);
  const auto words = sum.words();
  const std::vector<std::int64_t> all = gather_all(std::vector<std::int64_t>(words.begin(), words.end()), ranks);
  ExactSum total;
  for (std::size_t k = 0; k + ExactSum::kWords <= all.size(); k += ExactSum::kWords)
    total.add(ExactSum::from_words(all.data() + k));
  return total.value();
}

GroupCatalogue find_fof_groups_across_ranks(const ParticleSet& mine, const FofParameters& p, Collectives* ranks) {
  if (!(p.linking_length > 0.0)) throw InputError("friends-of-friends needs a positive linking length");
  const int count = ranks == nullptr ? 1 : ranks->size(), me = ranks == nullptr ? 0 : ranks->rank();
  const double l = p.linking_length, box = p.box;
  auto primary_type = [&](int t) { return std::find(p.linking_types.begin(), p.linking_types.end(), t) != p.linking_types.end(); };

  // Each particle to the owner of its slab; a slab's particles by ID.
  std::vector<Record> own(mine.size());
  for (std::size_t i = 0; i < mine.size(); ++i)
    own[i] = {mine.x[i], mine.v[i], mine.mass[i], mine.id[i], static_cast<std::uint64_t>(i), mine.type[i], 0};
  const Slabs slabs = into_slabs(own, box, ranks);

  // Each own particle's group (its label) and the group's home, where it has enough primaries
  // (-1 elsewhere); what the linking needs is freed before the groups' properties are found.
  std::vector<MemberRef> members;
  std::vector<std::uint64_t> group_label(own.size(), 0);
  std::vector<std::int32_t> home_of(own.size(), -1);
  {
    // Copies of the primaries within a linking length of another slab go to its owner (with a
    // margin: a copy too many links nothing that is not linked anyway).
    std::vector<char> exported(own.size(), 0);
    std::vector<Record> copies;
    if (ranks != nullptr) {
      const double reach = l * (1.0 + 1e-6);
      std::vector<std::vector<Record>> to(static_cast<std::size_t>(count));
      for (std::size_t k = 0; k < own.size(); ++k) {
        if (!primary_type(own[k].type)) continue;
        for (int q = 0; q < count; ++q)
          if (q != me && slabs.near(own[k].x.x, q, reach)) {
            to[static_cast<std::size_t>(q)].push_back(own[k]);
            exported[k] = 1;
          }
      }
      copies = exchange(to, ranks);
    }

    // The primaries linked here, own and copies, by ID: the root of a component is then its
    // smallest ID, and the nearest-primary ties go to the smaller ID, as on one rank.
    struct Linked {
      std::uint64_t id, origin;
      std::uint32_t at;  // in own, or in copies
      bool copy;
    };
    std::vector<Linked> linked;
    for (std::size_t k = 0; k < own.size(); ++k)
      if (primary_type(own[k].type)) linked.push_back({own[k].id, own[k].origin, static_cast<std::uint32_t>(k), false});
    for (std::size_t k = 0; k < copies.size(); ++k) linked.push_back({copies[k].id, copies[k].origin, static_cast<std::uint32_t>(k), true});
    std::sort(linked.begin(), linked.end(),
              [](const Linked& a, const Linked& b) { return std::tie(a.id, a.copy, a.origin) < std::tie(b.id, b.copy, b.origin); });
    std::vector<Vec3> px(linked.size());
    for (std::size_t k = 0; k < linked.size(); ++k) px[k] = linked[k].copy ? copies[linked[k].at].x : own[linked[k].at].x;
    const PointGrid grid(px, l, box);
    const std::vector<std::uint32_t> root = link_friends(grid, px, l);

    // Components joined across slabs: every copy, and every primary copied elsewhere, ties its
    // ID to its component's label (smallest ID) here; the union over all ranks is the same on each.
    IdUnion joins;
    if (ranks != nullptr) {
      std::vector<std::array<std::uint64_t, 2>> ties;
      for (std::size_t k = 0; k < linked.size(); ++k)
        if (linked[k].copy || exported[linked[k].at]) ties.push_back({linked[k].id, linked[root[k]].id});
      for (const auto& [a, b] : gather_all(ties, ranks)) joins.unite(a, b);
    }
    std::vector<std::uint64_t> label(linked.size());
    for (std::size_t k = 0; k < linked.size(); ++k) label[k] = joins.find(linked[root[k]].id);

    // Primaries per group over every rank. A label the joins never met is a component this
    // rank holds whole; the others' counts are summed, and their home is the rank that owns
    // the label's particle.
    std::unordered_map<std::uint64_t, std::uint64_t> primaries;
    std::unordered_set<std::uint64_t> own_labels;  // labels whose particle is this rank's
    for (std::size_t k = 0; k < linked.size(); ++k)
      if (!linked[k].copy) {
        ++primaries[label[k]];
        if (label[k] == linked[k].id) own_labels.insert(label[k]);
      }
    struct Share {
      std::uint64_t label, primaries;
      std::int64_t home;  // this rank where it owns the label's particle, else -1
    };
    std::vector<Share> shares;
    for (const auto& [g, n] : primaries)
      if (joins.contains(g)) shares.push_back({g, n, own_labels.count(g) != 0 ? me : -1});
    std::sort(shares.begin(), shares.end(), [](const Share& a, const Share& b) { return a.label < b.label; });
    std::unordered_map<std::uint64_t, std::pair<std::uint64_t, int>> shared;  // label: (primaries, home)
    for (const Share& s : gather_all(shares, ranks)) {
      auto& [n, home] = shared.try_emplace(s.label, 0, -1).first->second;
      n += s.primaries;
      if (s.home >= 0) home = static_cast<int>(s.home);
    }
    // (primaries, home) of the group labelled g.
    auto group_of = [&](std::uint64_t g) -> std::pair<std::uint64_t, int> {
      if (const auto it = shared.find(g); it != shared.end()) return it->second;
      return {primaries.at(g), me};
    };

    // Every member to its group's home: primaries by their label, the others by the label of
    // their nearest primary within the linking length (own or copied: it is within l of this slab).
    std::vector<char> in_group(own.size(), 0);
    for (std::size_t k = 0; k < linked.size(); ++k)
      if (!linked[k].copy) group_label[linked[k].at] = label[k], in_group[linked[k].at] = 1;
    {
      std::vector<std::uint32_t> others;
      std::vector<Vec3> ox;
      for (std::size_t k = 0; k < own.size(); ++k)
        if (!primary_type(own[k].type)) others.push_back(static_cast<std::uint32_t>(k)), ox.push_back(own[k].x);
      const std::vector<std::int64_t> host = nearest_within(grid, px, ox, l);
      for (std::size_t q = 0; q < others.size(); ++q)
        if (host[q] >= 0) group_label[others[q]] = label[static_cast<std::size_t>(host[q])], in_group[others[q]] = 1;
    }
    for (std::size_t k = 0; k < own.size(); ++k) {
      if (!in_group[k]) continue;
      const auto [n, home] = group_of(group_label[k]);
      if (n >= p.min_members) home_of[k] = home;
    }
  }

  // The members of the groups homed here: this rank's own (by index) and those other ranks
  // send (kept as guests), by group, then type, then ID.
  std::vector<Record> guests;
  {
    std::vector<std::vector<Member>> to(static_cast<std::size_t>(count));
    for (std::size_t k = 0; k < own.size(); ++k)
      if (home_of[k] >= 0 && home_of[k] != me) to[static_cast<std::size_t>(home_of[k])].push_back({group_label[k], own[k]});
    std::vector<Member> arrived = exchange(to, ranks);
    guests.reserve(arrived.size());
    for (const Member& m : arrived) guests.push_back(m.r);
    std::vector<MemberRef> refs;
    for (std::size_t k = 0; k < own.size(); ++k)
      if (home_of[k] == me) refs.push_back({group_label[k], k});
    for (std::size_t k = 0; k < arrived.size(); ++k) refs.push_back({arrived[k].group, own.size() + k});
    members.swap(refs);
  }
  std::vector<std::int32_t>().swap(home_of);
  std::vector<std::uint64_t>().swap(group_label);
  auto record = [&](const MemberRef& m) -> const Record& { return m.at < own.size() ? own[m.at] : guests[m.at - own.size()]; };
  std::sort(members.begin(), members.end(), [&](const MemberRef& a, const MemberRef& b) {
    const Record &ra = record(a), &rb = record(b);
    return std::tie(a.group, ra.type, ra.id, ra.origin) < std::tie(b.group, rb.type, rb.id, rb.origin);
  });
  std::vector<std::size_t> first;  // each home group's members: [first[g], first[g + 1])
  for (std::size_t k = 0; k < members.size(); ++k)
    if (k == 0 || members[k].group != members[k - 1].group) first.push_back(k);
  const std::size_t homed = first.size();
  first.push_back(members.size());

  // Each home group's mass, centres and velocity, on its members' own potential.
  std::vector<GroupSummary> summary(homed);
  std::vector<double> extent(homed, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, homed, 1), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      GroupSummary& s = summary[g];
      const std::size_t n = first[g + 1] - first[g];
      auto at = [&](std::size_t k) -> const Record& { return record(members[first[g] + k]); };
      const Vec3 reference = at(0).x;
      std::vector<Vec3> local(n);
      std::vector<double> mass(n);
      Vec3 moment{}, momentum{};
      s.smallest_id = at(0).id;
      for (std::size_t k = 0; k < n; ++k) {
        const Record& r = at(k);
        local[k] = nearest_image(reference, r.x, box);
        mass[k] = r.m;
        s.mass += mass[k];
        const auto t = static_cast<std::size_t>(std::clamp(r.type, 0, 5));
        s.mass_by_type[t] += mass[k];
        ++s.count_by_type[t];
        moment += local[k] * mass[k];
        momentum += r.v * mass[k];
        s.smallest_id = std::min(s.smallest_id, r.id);
      }
      s.members = n;
      s.centre_of_mass = folded(reference + moment * (1.0 / s.mass), box);
      s.velocity = momentum * (1.0 / s.mass);
      const std::size_t centre = potential_minimum(local, mass, p.softening, p.G);
      s.potential_minimum = folded(reference + local[centre], box);
      for (const Vec3& x : local) extent[g] = std::max(extent[g], norm(x - local[centre]));
    }
  });

  // M_200 about the potential minimum, from every rank's particles about it, in rounds of
  // doubling radii until each group's mean density has fallen to the threshold.
  if (p.overdensity > 0.0) {
    const double limit = box > 0.0 ? 0.5 * box : std::numeric_limits<double>::infinity();
    const double shell = 4.0 / 3.0 * std::numbers::pi * p.overdensity;
    std::vector<double> radius(homed);
    std::vector<char> done(homed, 0);
    for (std::size_t g = 0; g < homed; ++g) radius[g] = std::min(std::max(extent[g], 2.0 * l), limit);
    std::vector<Vec3> x(own.size());
    for (std::size_t k = 0; k < own.size(); ++k) x[k] = own[k].x;
    const PointGrid all(x, 2.0 * l, box);
    for (;;) {
      std::vector<ShellQuery> asked;
      for (std::size_t g = 0; g < homed; ++g)
        if (!done[g]) asked.push_back({summary[g].potential_minimum, radius[g], g, me, 0});
      const std::vector<ShellQuery> queries = gather_all(asked, ranks);
      if (queries.empty()) break;
      // Each query's particles here, then to the query's home.
      std::vector<std::vector<ShellAnswer>> found(queries.size());
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t q = range.begin(); q != range.end(); ++q) {
          const ShellQuery& query = queries[q];
          const int reach = static_cast<int>(std::ceil(query.radius / all.cell_size()));
          all.for_each_cell_near(all.cell_of(query.centre), reach, [&](std::size_t c) {
            const PointGrid::Cell& cell = all.cells()[c];
            for (std::uint32_t i = cell.first; i < cell.first + cell.count; ++i) {
              const std::uint32_t j = all.order()[i];
              const double r = norm(all.separation(query.centre, x[j]));
              if (r <= query.radius) found[q].push_back({query.slot, r, own[j].m});
            }
          });
        }
      });
      std::vector<std::vector<ShellAnswer>> answers(static_cast<std::size_t>(count));
      for (std::size_t q = 0; q < queries.size(); ++q) {
        auto& out = answers[static_cast<std::size_t>(queries[q].home)];
        out.insert(out.end(), found[q].begin(), found[q].end());
      }
      std::vector<std::vector<ShellAnswer>>().swap(found);
      const std::vector<ShellAnswer> arrived = exchange(answers, ranks);
      // Each group's (r, m) together, then sorted and read group by group in parallel.
      std::vector<std::size_t> from(homed + 1, 0);
      for (const ShellAnswer& a : arrived) ++from[a.slot + 1];
      for (std::size_t g = 0; g < homed; ++g) from[g + 1] += from[g];
      std::vector<std::pair<double, double>> inside(arrived.size());
      {
        std::vector<std::size_t> next(from.begin(), from.end() - 1);
        for (const ShellAnswer& a : arrived) inside[next[a.slot]++] = {a.r, a.m};
      }
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, homed, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
          if (done[g]) continue;
          const std::span<std::pair<double, double>> about = std::span(inside).subspan(from[g], from[g + 1] - from[g]);
          std::sort(about.begin(), about.end());
          if (const auto so = overdensity_crossing(about, radius[g], limit, shell)) {
            summary[g].r200 = so->radius;
            summary[g].m200 = so->mass;
            done[g] = 1;
          } else {
            radius[g] = std::min(2.0 * radius[g], limit);
          }
        }
      });
    }
  }

  // The catalogue on rank 0: by mass, ties by the smallest member ID.
  std::vector<MemberName> names(members.size());
  for (std::size_t k = 0; k < members.size(); ++k) {
    const Record& r = record(members[k]);
    names[k] = {r.id, r.origin, r.type, 0};
  }
  std::vector<MemberRef>().swap(members);
  std::vector<Record>().swap(guests);
  const std::vector<GroupSummary> summaries = on_rank_zero(std::move(summary), ranks);
  const std::vector<MemberName> all_names = on_rank_zero(std::move(names), ranks);
  if (me != 0) return {};
  std::vector<std::size_t> start(summaries.size() + 1, 0);
  for (std::size_t g = 0; g < summaries.size(); ++g) start[g + 1] = start[g] + summaries[g].members;
  if (start.back() != all_names.size()) throw std::logic_error("friends-of-friends: members and groups disagree");
  std::vector<std::size_t> order(summaries.size());
  for (std::size_t g = 0; g < order.size(); ++g) order[g] = g;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (summaries[a].mass != summaries[b].mass) return summaries[a].mass > summaries[b].mass;
    return summaries[a].smallest_id < summaries[b].smallest_id;
  });
  GroupCatalogue out;
  out.groups.resize(order.size());
  out.member_id.reserve(all_names.size());
  out.member_type.reserve(all_names.size());
  out.member_origin.reserve(all_names.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const GroupSummary& s = summaries[order[k]];
    Group& g = out.groups[k];
    g.mass = s.mass;
    g.mass_by_type = s.mass_by_type;
    g.count_by_type = s.count_by_type;
    g.centre_of_mass = s.centre_of_mass;
    g.potential_minimum = s.potential_minimum;
    g.velocity = s.velocity;
    g.m200 = s.m200;
    g.r200 = s.r200;
    for (std::size_t m = start[order[k]]; m < start[order[k] + 1]; ++m) {
      g.members.push_back(static_cast<std::uint32_t>(out.member_id.size()));
      out.member_id.push_back(all_names[m].id);
      out.member_type.push_back(all_names[m].type);
      out.member_origin.push_back(all_names[m].origin);
    }
  }
  return out;
}

}  // namespace fountain::groups
