#include "groups/FofCatalogue.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "core/Error.hpp"
#include "groups/FofAcrossRanks.hpp"

namespace fountain::groups {

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
    if (const auto so = overdensity_crossing(inside, radius, limit, shell)) return *so;
    radius = std::min(2.0 * radius, limit);
  }
}

std::optional<SphericalOverdensity> overdensity_crossing(std::span<const std::pair<double, double>> inside, double radius,
                                                         double limit, double shell) {
  double enclosed = 0.0;
  for (const auto& [r, m] : inside) {
    // Inside the shell before this particle the enclosed mass is `enclosed`: the mean density
    // falls to the threshold there if this particle's radius is beyond the crossing.
    if (enclosed > 0.0 && enclosed < shell * r * r * r) return SphericalOverdensity{std::cbrt(enclosed / shell), enclosed};
    enclosed += m;
  }
  if (enclosed < shell * radius * radius * radius) return SphericalOverdensity{std::cbrt(enclosed / shell), enclosed};
  if (radius >= limit) return SphericalOverdensity{radius, enclosed};  // still above the threshold at half the box
  return std::nullopt;
}

std::vector<Group> find_fof_groups(const ParticleSet& particles, const FofParameters& p) {
  GroupCatalogue found = find_fof_groups_across_ranks(particles, p, nullptr);
  for (Group& g : found.groups)
    for (std::uint32_t& m : g.members) m = static_cast<std::uint32_t>(found.member_origin[m]);
  return std::move(found.groups);
}

}  // namespace fountain::groups
