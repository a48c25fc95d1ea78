// HOP groups (Eisenstein & Hut 1998, with the authors' regroup step): hops to the densest neighbour, then merging at saddle densities.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::groups {

struct HopParameters {
  int n_dens = 64;   // neighbours of the density estimate (the particle itself counted)
  int n_hop = 16;    // neighbours among which a particle hops to the densest (itself counted)
  int n_merge = 4;   // neighbours (itself not counted) that define boundaries between groups
  // Densities, in the units of the estimate (mass per comoving volume): particles below
  // delta_outer belong to no group; a group is viable if its peak reaches delta_peak; viable
  // groups merge through boundaries of at least delta_saddle.
  double delta_outer = 0.0, delta_saddle = 0.0, delta_peak = 0.0;
  double box = 0.0;                  // > 0: periodic box of this side
  std::size_t min_members = 10;
};

struct HopGroup {
  std::vector<std::uint32_t> members;  // increasing index
  double mass = 0.0;
  double peak_density = 0.0;
  std::uint32_t peak = 0;              // the densest member
};

struct HopResult {
  std::vector<double> density;
  std::vector<std::int64_t> group;     // per particle: its group in `groups`, or -1
  std::vector<HopGroup> groups;        // largest first (ties: the group of the lower peak index)
};

// Densities with the M4 spline over each particle's n_dens nearest (h = half the distance to
// the n_dens-th, itself counted), symmetrised: rho_i = sum_j (m_j / 2) (W(r_ij, h_i) + W(r_ij, h_j)),
// j = i included. The same for any thread count.
std::vector<double> hop_densities(std::span<const Vec3> x, std::span<const double> mass, int n_dens, double box);

// HOP's groups, as the authors' hop and regroup programs make them (docs/groups.md); ties in
// distance and density go to the lower index (find_hop_groups_across_ranks alone, with the
// indices as IDs).
HopResult find_hop_groups(std::span<const Vec3> x, std::span<const double> mass, const HopParameters& p);

}  // namespace fountain::groups
