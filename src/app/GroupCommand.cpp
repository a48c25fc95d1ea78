#include "app/GroupCommand.hpp"

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>

#include "core/Error.hpp"
#include "cosmology/Background.hpp"
#include "groups/FofAcrossRanks.hpp"
#include "groups/FofCatalogue.hpp"
#include "groups/Hop.hpp"
#include "groups/HopAcrossRanks.hpp"
#include "groups/SlabsAcrossRanks.hpp"
#include "io/GroupFiles.hpp"

namespace fountain {

namespace {

std::unique_ptr<tbb::global_control> limit_threads(int threads) {
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<std::size_t>(threads));
}


}  // namespace

std::string find_hop_groups(const HopRequest& request) {
  const io::GroupInput in = io::read_group_input(request.snapshot);
  // Baryons only: gas with its hidden stellar mass, and stars.
  groups::ParticleSet baryons;
  std::vector<double> hidden;
  const groups::ParticleSet& set = in.particles;
  for (std::size_t i = 0; i < set.size(); ++i)
    if (set.type[i] == 0 || set.type[i] == 4) {
      baryons.push_back(set.x[i], set.v[i], set.mass[i], set.id[i], set.type[i]);
      hidden.push_back(in.hidden_mass[i]);
    }
  return find_hop_groups(request, baryons, hidden, in, nullptr);
}

std::string find_hop_groups(const HopRequest& request, const groups::ParticleSet& baryons, std::span<const double> hidden,
                            const io::GroupInput& header, Collectives* ranks) {
  const auto start = std::chrono::steady_clock::now();
  const auto threads = limit_threads(request.threads);
  const std::uint64_t count = groups::count_over_ranks(baryons.size(), ranks);
  if (count == 0) throw InputError(fmt::format("{}: no gas or star particles for HOP", request.snapshot));
  const double omega_b = request.omega_b >= 0.0 ? request.omega_b : header.omega_b;
  if (!header.cosmological || !(omega_b > 0.0))
    throw InputError(fmt::format("{}: HOP's thresholds are in mean baryon densities, Omega_b rho_crit0: the snapshot "
                                 "{}; give --omega-b",
                                 request.snapshot, header.cosmological ? "has no OmegaBaryon" : "is not cosmological"));
  groups::HopParameters p;
  const double mean = omega_b * cosmology::critical_density0_in(header.units);
  p.n_dens = request.n_dens;
  p.n_hop = request.n_hop;
  p.n_merge = request.n_merge;
  p.delta_outer = request.outer * mean;
  p.delta_saddle = request.saddle_factor * p.delta_outer;
  p.delta_peak = request.peak_factor * p.delta_outer;
  p.box = header.box;
  const groups::HopCatalogue hop = groups::find_hop_groups_across_ranks(baryons, hidden, p, ranks);
  if (ranks != nullptr && ranks->rank() != 0) return {};
  io::write_hop_catalogue(request.output, hop, header, {request.snapshot, p, mean});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string largest = hop.groups.empty()
                                  ? std::string("none")
                                  : fmt::format("the largest {:.4g} with {} members", hop.groups[0].mass,
                                                hop.groups[0].members.size());
  return fmt::format("wrote {} ({} HOP groups among {} baryonic particles, delta_outer = {:g} mean baryon densities; "
                     "{}) in {:.2f} s",
                     request.output, hop.groups.size(), count, request.outer, largest, seconds);
}

std::string find_groups(const FofRequest& request) {
  const io::GroupInput in = io::read_group_input(request.snapshot);
  return find_groups(request, in.particles, in, nullptr);
}

std::string find_groups(const FofRequest& request, const groups::ParticleSet& mine, const io::GroupInput& header,
                        Collectives* ranks) {
  const auto start = std::chrono::steady_clock::now();
  const auto threads = limit_threads(request.threads);
  for (int t : request.linking_types)
    if (t < 0 || t > 5) throw InputError(fmt::format("option --link-types: {} is not a GADGET particle type (0-5)", t));

  // The mean density the primaries stand for: all matter but the baryons (COSMOLOGY.md C9.1),
  // or all matter when the snapshot has no gas or stars. Summed so that any split of the
  // particles between ranks gives the same linking length.
  const double G = header.units.gravitational_constant();
  const double rho_crit0 = cosmology::critical_density0_in(header.units);
  std::vector<double> primary_masses, gas_masses, dm_masses;
  std::uint64_t baryons = 0;
  for (std::size_t i = 0; i < mine.size(); ++i) {
    const int t = mine.type[i];
    if (std::find(request.linking_types.begin(), request.linking_types.end(), t) != request.linking_types.end())
      primary_masses.push_back(mine.mass[i]);
    if (t == 0 || t == 4) ++baryons;
    if (t == 0) gas_masses.push_back(mine.mass[i]);
    if (t == 1) dm_masses.push_back(mine.mass[i]);
  }
  const std::uint64_t primaries = groups::count_over_ranks(primary_masses.size(), ranks);
  const std::uint64_t gas = groups::count_over_ranks(gas_masses.size(), ranks);
  const std::uint64_t dm = groups::count_over_ranks(dm_masses.size(), ranks);
  baryons = groups::count_over_ranks(baryons, ranks);
  const double primary_mass = groups::sum_in_any_order(primary_masses, ranks);
  const double gas_mass = groups::sum_in_any_order(gas_masses, ranks);
  const double dm_mass = groups::sum_in_any_order(dm_masses, ranks);
  std::vector<double>().swap(primary_masses);
  std::vector<double>().swap(gas_masses);
  std::vector<double>().swap(dm_masses);
  if (primaries == 0)
    throw InputError(fmt::format("{}: no particles of the linking types to link", request.snapshot));
  double l = request.linking_length;
  double omega_b = 0.0;
  if (!(l > 0.0)) {
    if (!header.cosmological)
      throw InputError(fmt::format("{}: not a cosmological snapshot (no Omega0 and Time in /Header): give the linking "
                                   "length with --linking-length",
                                   request.snapshot));
    if (baryons > 0) {
      // The header's Omega_b, else the high-resolution gas's share of the matter (the ICs split
      // each cell's matter between one gas and one dark matter particle).
      omega_b = header.omega_b >= 0.0
                    ? header.omega_b
                    : (gas > 0 && dm > 0 ? header.omega_m * (gas_mass / static_cast<double>(gas)) /
                                               (gas_mass / static_cast<double>(gas) + dm_mass / static_cast<double>(dm))
                                         : 0.0);
    }
    l = groups::linking_length(request.b, primary_mass / static_cast<double>(primaries),
                               (header.omega_m - omega_b) * rho_crit0);
  }
  groups::FofParameters p;
  p.linking_length = l;
  p.linking_types = request.linking_types;
  p.min_members = request.min_members;
  p.box = header.box;
  p.G = G;
  p.softening = l / (5.0 * request.b / 0.2);  // 1/25 of the mean spacing, a usual softening
  if (header.cosmological) {
    // 200 rho_crit(z) as a comoving density: 200 rho_crit0 E(a)^2 a^3.
    const cosmology::Background bg({header.omega_m, header.omega_lambda, std::max(omega_b, 0.0), header.hubble_param});
    const double a = header.time, e = bg.E(a);
    p.overdensity = 200.0 * rho_crit0 * e * e * a * a * a;
  }
  const std::uint64_t particles = groups::count_over_ranks(mine.size(), ranks);
  const groups::GroupCatalogue found = groups::find_fof_groups_across_ranks(mine, p, ranks);
  if (ranks != nullptr && ranks->rank() != 0) return {};
  io::FofCatalogueInfo info{request.snapshot, l, request.b, request.min_members, request.linking_types, p.overdensity};
  io::write_fof_catalogue(request.output, found, header, info);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::vector<groups::Group>& g = found.groups;
  std::string largest = g.empty() ? std::string("none")
                                  : fmt::format("the largest {:.4g} with {} members, M_200 = {:.4g}", g[0].mass,
                                                g[0].members.size(), g[0].m200);
  return fmt::format("wrote {} ({} groups of at least {} primaries among {} particles, linking length {:.5g}; {}) in {:.2f} s",
                     request.output, g.size(), request.min_members, particles, l, largest, seconds);
}

}  // namespace fountain
