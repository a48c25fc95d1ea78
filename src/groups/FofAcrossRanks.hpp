// Friends-of-friends groups of particles that several ranks hold: slabs of the box linked with copies of their margins, joined by particle ID.
#pragma once
#include <cstdint>
#include <vector>

#include "core/Collectives.hpp"
#include "groups/FofCatalogue.hpp"

namespace fountain::groups {

// A catalogue as rank 0 writes it: the groups in find_fof_groups' order, each group's
// `members` indexing the member lists below (each group's by type, then ID).
struct GroupCatalogue {
  std::vector<Group> groups;
  std::vector<std::uint64_t> member_id;
  std::vector<int> member_type;
  std::vector<std::uint64_t> member_origin;  // each member's index in its rank's `mine`
};

// The groups find_fof_groups finds in the union of every rank's `mine`, the same bit for bit
// whatever the ranks and however the particles are spread over them (ranks null: this
// process alone). Particle IDs must be unique across the ranks. Each rank sends its
// particles to the owner of their slab of x (slabs of equal particle count), and each slab's
// owner links its own primaries with copies of the others' primaries within a linking
// length of it; components are joined across slabs through the IDs of those copies. Each
// group's properties are found on the rank of its smallest primary ID, spherical
// overdensities by asking every rank for its particles about the centre. Rank 0 returns the
// catalogue, the others an empty one: rank 0 holds the groups and their members' IDs, never
// the particles. Every rank calls it.
GroupCatalogue find_fof_groups_across_ranks(const ParticleSet& mine, const FofParameters& p, Collectives* ranks);

// The sum of values over every rank, exact until rounded once (core/ExactSum.hpp): the same
// whatever their order or their split between ranks.
double sum_in_any_order(const std::vector<double>& mine, Collectives* ranks);

}  // namespace fountain::groups
