#include "groups/FofCatalogue.hpp"

#include <cmath>
#include <utility>

#include "core/Error.hpp"
#include "groups/FofAcrossRanks.hpp"

namespace fountain::groups {

double linking_length(double b, double mean_mass, double mean_density) {
  if (!(mean_mass > 0.0) || !(mean_density > 0.0)) throw InputError("the linking length needs a positive mean mass and density");
  return b * std::cbrt(mean_mass / mean_density);
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
