// Friends-of-friends groups and their properties: masses by type, centres, velocity, and M_200 about the potential minimum.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::groups {

// The particles groups are found among, with their GADGET types (0 gas, 1 dark matter, 2
// low-resolution dark matter, 4 stars). Positions comoving; velocities as the caller wants
// them reported.
struct ParticleSet {
  std::vector<Vec3> x, v;
  std::vector<double> mass;
  std::vector<std::uint64_t> id;
  std::vector<int> type;
  std::size_t size() const { return x.size(); }
  void push_back(const Vec3& xi, const Vec3& vi, double m, std::uint64_t i, int t) {
    x.push_back(xi), v.push_back(vi), mass.push_back(m), id.push_back(i), type.push_back(t);
  }
};

struct FofParameters {
  double linking_length = 0.0;        // comoving
  std::vector<int> linking_types{1};  // the primaries; every other type attaches to them
  std::size_t min_members = 32;       // primaries a group needs
  double box = 0.0;                   // > 0: periodic box of this side
  double G = 1.0;                     // for the groups' own potential
  double softening = 0.0;             // Plummer-equivalent, for that potential
  double overdensity = 0.0;           // the mean density within R_200 (200 rho_crit(z), comoving)
};

struct Group {
  double mass = 0.0;
  std::array<double, 6> mass_by_type{};
  std::array<std::uint64_t, 6> count_by_type{};
  Vec3 centre_of_mass, potential_minimum, velocity;
  double m200 = 0.0, r200 = 0.0;
  std::vector<std::uint32_t> members;  // indices into the ParticleSet, by type then ID
};

// b (mean_mass / mean_density)^(1/3): b times the mean spacing of particles of that mass.
double linking_length(double b, double mean_mass, double mean_density);

// Groups of at least min_members primaries linked at the linking length (nearest images when
// periodic); each particle of another type joins the group of its nearest primary closer than
// the linking length (ties to the smaller ID). Each group's members are taken by type, then
// ID: its potential minimum is found on their own potential (a tree walk on the group alone,
// softened by `softening`; ties to the first), and M_200, R_200 are the mass and radius within
// which the mean density of all particles about that centre is `overdensity`. Ordered by mass,
// ties by the smallest member ID. The same for any thread count or order of the particles
// (find_fof_groups_across_ranks alone).
std::vector<Group> find_fof_groups(const ParticleSet& particles, const FofParameters& p);

// The radius about a centre within which the mean density of the particles first falls to a
// threshold density (the enclosed mass is a step function of r, so R = (3 M / (4 pi density))^(1/3)
// for the mass M inside the first shell where it drops), and that mass, from the (r, m) of
// every particle within `radius` of the centre, sorted: the answer, or nothing when the mean
// density is still above the threshold (shell = 4 pi density / 3) at `radius` < `limit`, half
// a periodic box. The answer does not depend on `radius` once there is one.
struct SphericalOverdensity {
  double radius = 0.0, mass = 0.0;
};
std::optional<SphericalOverdensity> overdensity_crossing(std::span<const std::pair<double, double>> inside, double radius,
                                                         double limit, double shell);

}  // namespace fountain::groups
