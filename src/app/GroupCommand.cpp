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
#include "groups/FofCatalogue.hpp"
#include "groups/Hop.hpp"
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
  const auto start = std::chrono::steady_clock::now();
  const auto threads = limit_threads(request.threads);
  const io::GroupInput in = io::read_group_input(request.snapshot);
  const groups::ParticleSet& set = in.particles;
  // Baryons only: gas with its hidden stellar mass, and stars.
  std::vector<std::uint32_t> members;
  std::vector<Vec3> x;
  std::vector<double> mass;
  for (std::size_t i = 0; i < set.size(); ++i)
    if (set.type[i] == 0 || set.type[i] == 4) {
      members.push_back(static_cast<std::uint32_t>(i));
      x.push_back(set.x[i]);
      mass.push_back(set.mass[i] + in.hidden_mass[i]);
    }
  if (members.empty()) throw InputError(fmt::format("{}: no gas or star particles for HOP", request.snapshot));
  const double omega_b = request.omega_b >= 0.0 ? request.omega_b : in.omega_b;
  if (!in.cosmological || !(omega_b > 0.0))
    throw InputError(fmt::format("{}: HOP's thresholds are in mean baryon densities, Omega_b rho_crit0: the snapshot "
                                 "{}; give --omega-b",
                                 request.snapshot, in.cosmological ? "has no OmegaBaryon" : "is not cosmological"));
  groups::HopParameters p;
  const double mean = omega_b * cosmology::critical_density0_in(in.units);
  p.n_dens = request.n_dens;
  p.n_hop = request.n_hop;
  p.n_merge = request.n_merge;
  p.delta_outer = request.outer * mean;
  p.delta_saddle = request.saddle_factor * p.delta_outer;
  p.delta_peak = request.peak_factor * p.delta_outer;
  p.box = in.box;
  const groups::HopResult hop = groups::find_hop_groups(x, mass, p);
  io::write_hop_catalogue(request.output, hop, members, mass, in, {request.snapshot, p, mean});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string largest = hop.groups.empty()
                                  ? std::string("none")
                                  : fmt::format("the largest {:.4g} with {} members", hop.groups[0].mass,
                                                hop.groups[0].members.size());
  return fmt::format("wrote {} ({} HOP groups among {} baryonic particles, delta_outer = {:g} mean baryon densities; "
                     "{}) in {:.2f} s",
                     request.output, hop.groups.size(), members.size(), request.outer, largest, seconds);
}

std::string find_groups(const FofRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  const auto threads = limit_threads(request.threads);
  const io::GroupInput in = io::read_group_input(request.snapshot);
  const groups::ParticleSet& set = in.particles;
  for (int t : request.linking_types)
    if (t < 0 || t > 5) throw InputError(fmt::format("option --link-types: {} is not a GADGET particle type (0-5)", t));

  // The mean density the primaries stand for: all matter but the baryons (COSMOLOGY.md C9.1),
  // or all matter when the snapshot has no gas or stars.
  const double G = in.units.gravitational_constant();
  const double rho_crit0 = cosmology::critical_density0_in(in.units);
  double primary_mass = 0.0, gas_mass = 0.0, dm_mass = 0.0;
  std::size_t primaries = 0, baryons = 0, gas = 0, dm = 0;
  for (std::size_t i = 0; i < set.size(); ++i) {
    const int t = set.type[i];
    if (std::find(request.linking_types.begin(), request.linking_types.end(), t) != request.linking_types.end())
      primary_mass += set.mass[i], ++primaries;
    if (t == 0 || t == 4) ++baryons;
    if (t == 0) gas_mass += set.mass[i], ++gas;
    if (t == 1) dm_mass += set.mass[i], ++dm;
  }
  if (primaries == 0)
    throw InputError(fmt::format("{}: no particles of the linking types to link", request.snapshot));
  double l = request.linking_length;
  double omega_b = 0.0;
  if (!(l > 0.0)) {
    if (!in.cosmological)
      throw InputError(fmt::format("{}: not a cosmological snapshot (no Omega0 and Time in /Header): give the linking "
                                   "length with --linking-length",
                                   request.snapshot));
    if (baryons > 0) {
      // The header's Omega_b, else the high-resolution gas's share of the matter (the ICs split
      // each cell's matter between one gas and one dark matter particle).
      omega_b = in.omega_b >= 0.0 ? in.omega_b
                                  : (gas > 0 && dm > 0 ? in.omega_m * (gas_mass / gas) / (gas_mass / gas + dm_mass / dm) : 0.0);
    }
    l = groups::linking_length(request.b, primary_mass / static_cast<double>(primaries), (in.omega_m - omega_b) * rho_crit0);
  }
  groups::FofParameters p;
  p.linking_length = l;
  p.linking_types = request.linking_types;
  p.min_members = request.min_members;
  p.box = in.box;
  p.G = G;
  p.softening = l / (5.0 * request.b / 0.2);  // 1/25 of the mean spacing, a usual softening
  if (in.cosmological) {
    // 200 rho_crit(z) as a comoving density: 200 rho_crit0 E(a)^2 a^3.
    const cosmology::Background bg({in.omega_m, in.omega_lambda, std::max(omega_b, 0.0), in.hubble_param});
    const double a = in.time, e = bg.E(a);
    p.overdensity = 200.0 * rho_crit0 * e * e * a * a * a;
  }
  const std::vector<groups::Group> found = groups::find_fof_groups(set, p);
  io::FofCatalogueInfo info{request.snapshot, l, request.b, request.min_members, request.linking_types, p.overdensity};
  io::write_fof_catalogue(request.output, found, in, info);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::string largest = found.empty() ? std::string("none")
                                      : fmt::format("the largest {:.4g} with {} members, M_200 = {:.4g}", found[0].mass,
                                                    found[0].members.size(), found[0].m200);
  return fmt::format("wrote {} ({} groups of at least {} primaries among {} particles, linking length {:.5g}; {}) in {:.2f} s",
                     request.output, found.size(), request.min_members, set.size(), l, largest, seconds);
}

}  // namespace fountain
