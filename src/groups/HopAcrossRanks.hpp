// HOP groups of particles that several ranks hold: slabs with margins wide enough for every particle's neighbours, hops and boundaries joined by ID.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/Collectives.hpp"
#include "groups/FofCatalogue.hpp"
#include "groups/Hop.hpp"

namespace fountain::groups {

// A HOP group as its catalogue records it.
struct HopCatalogueGroup {
  double mass = 0.0;                       // HOP masses: gas with its hidden stars, and stars
  std::array<double, 6> mass_by_type{};    // the particles' own masses; hidden stars under type 4
  std::array<std::uint64_t, 6> count_by_type{};
  double peak_density = 0.0;
  Vec3 peak, centre_of_mass, velocity;     // the densest member's position; periodic centre of mass
  std::uint64_t peak_member = 0;           // the densest member, in the member lists below
  std::vector<std::uint32_t> members;      // into the member lists, by increasing ID
};

// A catalogue as rank 0 writes it: groups largest first (ties: the group of the lower peak ID).
struct HopCatalogue {
  std::vector<HopCatalogueGroup> groups;
  std::vector<std::uint64_t> member_id, member_origin;  // origin: the index in its rank's `mine`
  std::vector<int> member_type;
  std::vector<double> member_density;
  std::vector<double> density;  // alone (ranks null): every particle's HOP density, by index in `mine`
};

// HOP (docs/groups.md) over the union of every rank's `mine`, with HOP masses mine.mass +
// hidden: the same catalogue bit for bit whatever the ranks and however the particles are
// spread, and the same as one process, which takes its particles by ID (ties in distance and
// density go to the lower ID; each particle's density scatters in increasing ID). Particle
// IDs must be unique. Each rank owns a slab of x with equal particle counts and copies of the
// particles within a margin of it, widened until every own particle's N_dens nearest lie in
// it; hops that leave a slab, the peaks' densities and the boundaries between groups are
// gathered by ID on every rank, which regroups alike; each group's properties are found on
// one rank, and rank 0 receives the groups and their members' IDs. Every rank calls it.
HopCatalogue find_hop_groups_across_ranks(const ParticleSet& mine, std::span<const double> hidden, const HopParameters& p,
                                          Collectives* ranks);

}  // namespace fountain::groups
