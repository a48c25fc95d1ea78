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
#include "io/GroupFiles.hpp"

namespace fountain {

namespace {

// H0 in a file's units: 100 km/s per Mpc/h in h-scaled units, whatever h is.
double hubble0_in(const Units& u) {
  const Units mpc_msun_kms;
  return cosmology::kHubbleInternal * (u.length_cgs / mpc_msun_kms.length_cgs) / (u.velocity_cgs / mpc_msun_kms.velocity_cgs);
}

}  // namespace

std::string find_groups(const FofRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<tbb::global_control> threads;
  if (request.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<std::size_t>(request.threads));
  const io::GroupInput in = io::read_group_input(request.snapshot);
  const groups::ParticleSet& set = in.particles;
  for (int t : request.linking_types)
    if (t < 0 || t > 5) throw InputError(fmt::format("option --link-types: {} is not a GADGET particle type (0-5)", t));

  // The mean density the primaries stand for: all matter but the baryons (COSMOLOGY.md C9.1),
  // or all matter when the snapshot has no gas or stars.
  const double G = in.units.gravitational_constant();
  const double hubble0 = hubble0_in(in.units);
  const double rho_crit0 = 3.0 * hubble0 * hubble0 / (8.0 * std::numbers::pi * G);
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
