#include "groups/Hop.hpp"

#include <limits>
#include <stdexcept>

#include "core/Error.hpp"
#include "groups/HopAcrossRanks.hpp"

namespace fountain::groups {

namespace {

// Particles identified by their index, for the one-process interface.
ParticleSet indexed(std::span<const Vec3> x, std::span<const double> mass) {
  if (mass.size() != x.size()) throw std::invalid_argument("HOP: one mass per position");
  ParticleSet set;
  for (std::size_t i = 0; i < x.size(); ++i) set.push_back(x[i], Vec3{}, mass[i], i, 0);
  return set;
}

}  // namespace

std::vector<double> hop_densities(std::span<const Vec3> x, std::span<const double> mass, int n_dens, double box) {
  if (n_dens < 2) throw InputError("HOP's density needs at least 2 neighbours");
  HopParameters p;
  p.n_dens = n_dens, p.n_hop = n_dens, p.n_merge = 1;
  // Thresholds no density reaches: the densities alone.
  p.delta_outer = p.delta_saddle = p.delta_peak = std::numeric_limits<double>::infinity();
  p.box = box;
  const std::vector<double> none(x.size(), 0.0);
  return find_hop_groups_across_ranks(indexed(x, mass), none, p, nullptr).density;
}

HopResult find_hop_groups(std::span<const Vec3> x, std::span<const double> mass, const HopParameters& p) {
  const std::vector<double> none(x.size(), 0.0);
  HopCatalogue c = find_hop_groups_across_ranks(indexed(x, mass), none, p, nullptr);
  HopResult out;
  out.density = std::move(c.density);
  out.density.resize(x.size());
  out.group.assign(x.size(), -1);
  for (const HopCatalogueGroup& g : c.groups) {
    HopGroup hg;
    hg.mass = g.mass;
    hg.peak_density = g.peak_density;
    hg.peak = static_cast<std::uint32_t>(c.member_origin[g.peak_member]);
    for (std::uint32_t m : g.members) {
      hg.members.push_back(static_cast<std::uint32_t>(c.member_origin[m]));
      out.group[c.member_origin[m]] = static_cast<std::int64_t>(out.groups.size());
    }
    out.groups.push_back(std::move(hg));
  }
  return out;
}

}  // namespace fountain::groups
