#include "groups/FofCatalogue.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>
#include <utility>

#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"
#include "groups/FriendsOfFriends.hpp"
#include "gravity/GravityTree.hpp"

namespace fountain::groups {

namespace {

Vec3 folded(const Vec3& x, double box) { return box > 0.0 ? wrap_into_box(x, Vec3{box, box, box}) : x; }

// The member of least potential (ties: the lowest index), from the group's own gravity: its
// members unwrapped about the first, walked on a tree of the group alone.
std::size_t potential_minimum(const std::vector<Vec3>& local, const std::vector<double>& mass, double softening, double G) {
  if (local.size() == 1) return 0;
  const std::vector<double> soft(local.size(), softening);
  const gravity::GravityTree tree(local, mass, soft);
  std::vector<gravity::GravityTarget> targets(local.size());
  for (std::size_t k = 0; k < local.size(); ++k) targets[k] = {local[k], softening, gravity::kNoOldAcceleration, static_cast<std::int64_t>(k)};
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

}  // namespace

double linking_length(double b, double mean_mass, double mean_density) {
  if (!(mean_mass > 0.0) || !(mean_density > 0.0)) throw InputError("the linking length needs a positive mean mass and density");
  return b * std::cbrt(mean_mass / mean_density);
}

SphericalOverdensity spherical_overdensity(const PointGrid& grid, const ParticleSet& particles, const Vec3& centre,
                                           double density, double start_radius) {
  const double limit = grid.box() > 0.0 ? 0.5 * grid.box() : std::numeric_limits<double>::infinity();
  double radius = std::min(std::max(start_radius, grid.cell_size()), limit);
  const auto& cells = grid.cells();
  const auto& order = grid.order();
  const double shell = 4.0 / 3.0 * std::numbers::pi * density;  // mass per r^3 at the threshold
  for (;;) {
    std::vector<std::pair<double, double>> inside;  // (r, m)
    const int reach = static_cast<int>(std::ceil(radius / grid.cell_size()));
    grid.for_each_cell_near(grid.cell_of(centre), reach, [&](std::size_t c) {
      for (std::uint32_t p = cells[c].first; p < cells[c].first + cells[c].count; ++p) {
        const std::uint32_t j = order[p];
        const double r = norm(grid.separation(centre, particles.x[j]));
        if (r <= radius) inside.emplace_back(r, particles.mass[j]);
      }
    });
    std::sort(inside.begin(), inside.end());
    double enclosed = 0.0;
    for (const auto& [r, m] : inside) {
      // Inside the shell before this particle the enclosed mass is `enclosed`: the mean density
      // falls to the threshold there if this particle's radius is beyond the crossing.
      if (enclosed > 0.0 && enclosed < shell * r * r * r) return {std::cbrt(enclosed / shell), enclosed};
      enclosed += m;
    }
    if (enclosed < shell * radius * radius * radius) return {std::cbrt(enclosed / shell), enclosed};
    if (radius >= limit) return {radius, enclosed};  // still above the threshold at half the box
    radius = std::min(2.0 * radius, limit);
  }
}

std::vector<Group> find_fof_groups(const ParticleSet& particles, const FofParameters& p) {
  if (!(p.linking_length > 0.0)) throw InputError("friends-of-friends needs a positive linking length");
  const double box = p.box;
  // Primaries link; the rest attach to their nearest primary.
  std::vector<std::uint32_t> primary, other;
  for (std::size_t i = 0; i < particles.size(); ++i)
    (std::find(p.linking_types.begin(), p.linking_types.end(), particles.type[i]) != p.linking_types.end() ? primary : other)
        .push_back(static_cast<std::uint32_t>(i));
  std::vector<Vec3> px(primary.size()), ox(other.size());
  for (std::size_t k = 0; k < primary.size(); ++k) px[k] = particles.x[primary[k]];
  for (std::size_t k = 0; k < other.size(); ++k) ox[k] = particles.x[other[k]];
  const PointGrid grid(px, p.linking_length, box);
  const std::vector<std::uint32_t> root = link_friends(grid, px, p.linking_length);
  const std::vector<std::int64_t> host = nearest_within(grid, px, ox, p.linking_length);

  // Components with enough primaries become groups, numbered by their root for now.
  std::vector<std::uint32_t> primaries_in(primary.size(), 0);
  for (std::uint32_t r : root) ++primaries_in[r];
  constexpr std::int64_t kNone = -1;
  std::vector<std::int64_t> slot(primary.size(), kNone);
  std::vector<Group> groups;
  for (std::size_t r = 0; r < primary.size(); ++r)
    if (primaries_in[r] >= p.min_members) {
      slot[r] = static_cast<std::int64_t>(groups.size());
      groups.emplace_back();
    }
  std::vector<std::int64_t> group_of(particles.size(), kNone);
  for (std::size_t k = 0; k < primary.size(); ++k) group_of[primary[k]] = slot[root[k]];
  for (std::size_t k = 0; k < other.size(); ++k)
    if (host[k] >= 0) group_of[other[k]] = slot[root[static_cast<std::size_t>(host[k])]];
  for (std::size_t i = 0; i < particles.size(); ++i)
    if (group_of[i] != kNone) groups[static_cast<std::size_t>(group_of[i])].members.push_back(static_cast<std::uint32_t>(i));

  // Spherical overdensity masses count every particle: a grid over all of them.
  const PointGrid all(particles.x, 2.0 * p.linking_length, box);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      Group& group = groups[g];
      const std::vector<std::uint32_t>& m = group.members;
      const Vec3 reference = particles.x[m.front()];
      std::vector<Vec3> local(m.size());
      std::vector<double> mass(m.size());
      Vec3 moment{}, momentum{};
      for (std::size_t k = 0; k < m.size(); ++k) {
        const std::uint32_t i = m[k];
        local[k] = box > 0.0 ? all.separation(reference, particles.x[i]) : particles.x[i] - reference;
        mass[k] = particles.mass[i];
        group.mass += mass[k];
        const auto t = static_cast<std::size_t>(std::clamp(particles.type[i], 0, 5));
        group.mass_by_type[t] += mass[k];
        ++group.count_by_type[t];
        moment += local[k] * mass[k];
        momentum += particles.v[i] * mass[k];
      }
      group.centre_of_mass = folded(reference + moment * (1.0 / group.mass), box);
      group.velocity = momentum * (1.0 / group.mass);
      const std::size_t centre = potential_minimum(local, mass, p.softening, p.G);
      group.potential_minimum = folded(reference + local[centre], box);
      double extent = 0.0;
      for (const Vec3& x : local) extent = std::max(extent, norm(x - local[centre]));
      if (p.overdensity > 0.0) {
        const SphericalOverdensity so = spherical_overdensity(all, particles, group.potential_minimum, p.overdensity, extent);
        group.r200 = so.radius;
        group.m200 = so.mass;
      }
      std::sort(group.members.begin(), group.members.end(), [&](std::uint32_t a, std::uint32_t b) {
        return std::tie(particles.type[a], particles.id[a]) < std::tie(particles.type[b], particles.id[b]);
      });
    }
  });
  // By mass, ties by the smallest member ID.
  std::vector<std::uint64_t> smallest_id(groups.size());
  for (std::size_t g = 0; g < groups.size(); ++g) {
    smallest_id[g] = particles.id[groups[g].members.front()];
    for (std::uint32_t i : groups[g].members) smallest_id[g] = std::min(smallest_id[g], particles.id[i]);
  }
  std::vector<std::size_t> rank(groups.size());
  for (std::size_t g = 0; g < groups.size(); ++g) rank[g] = g;
  std::sort(rank.begin(), rank.end(), [&](std::size_t a, std::size_t b) {
    if (groups[a].mass != groups[b].mass) return groups[a].mass > groups[b].mass;
    return smallest_id[a] < smallest_id[b];
  });
  std::vector<Group> sorted;
  sorted.reserve(groups.size());
  for (std::size_t g : rank) sorted.push_back(std::move(groups[g]));
  return sorted;
}

}  // namespace fountain::groups
