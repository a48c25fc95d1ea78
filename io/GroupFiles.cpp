#include "io/GroupFiles.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/Error.hpp"
#include "io/Hdf5File.hpp"

namespace fountain::io {

namespace {
constexpr const char* kHeader = "/Header";

double header_scalar(const hdf5::File& f, const char* name, double fallback, bool required) {
  if (!f.has_attribute(kHeader, name)) {
    if (required) f.fail(std::string(kHeader) + "/" + name, "is missing");
    return fallback;
  }
  const std::vector<double> v = f.read_attribute_doubles(kHeader, name);
  if (v.empty() || !std::isfinite(v[0])) f.fail(std::string(kHeader) + "/" + name, "is empty or not finite");
  return v[0];
}
// What both catalogues' headers say: the counts, and the snapshot's time, cosmology and path.
void write_catalogue_header(hdf5::File& f, std::size_t groups, std::size_t ids, const GroupInput& input,
                            const std::string& snapshot) {
  f.create_group(kHeader);
  f.write_attribute(kHeader, "Ngroups_Total", static_cast<std::int64_t>(groups));
  f.write_attribute(kHeader, "Nids_Total", static_cast<std::int64_t>(ids));
  f.write_attribute(kHeader, "BoxSize", input.box);
  f.write_attribute(kHeader, "Time", input.time);
  f.write_attribute(kHeader, "Redshift", input.cosmological ? 1.0 / input.time - 1.0 : 0.0);
  f.write_attribute(kHeader, "Omega0", input.omega_m);
  f.write_attribute(kHeader, "OmegaLambda", input.omega_lambda);
  f.write_attribute(kHeader, "HubbleParam", input.hubble_param);
  if (input.omega_b >= 0.0) f.write_attribute(kHeader, "OmegaBaryon", input.omega_b);
  f.write_attribute(kHeader, "UnitLength_in_cm", input.units.length_cgs);
  f.write_attribute(kHeader, "UnitMass_in_g", input.units.mass_cgs);
  f.write_attribute(kHeader, "UnitVelocity_in_cm_per_s", input.units.velocity_cgs);
  f.write_attribute(kHeader, "Snapshot", snapshot);
}
}  // namespace

GroupInput read_group_input(const std::string& path) {
  const hdf5::File f(path, hdf5::File::Mode::read);
  GroupInput in;
  if (header_scalar(f, "NumFilesPerSnapshot", 1.0, false) > 1.0)
    f.fail(kHeader, "the snapshot is split over several files; the group finders read single files");
  const std::vector<double> box = f.read_attribute_doubles(kHeader, "BoxSize");
  if (box.empty() || !(box[0] > 0.0)) f.fail(std::string(kHeader) + "/BoxSize", "is not a positive length");
  for (double b : box)
    if (b != box[0]) f.fail(std::string(kHeader) + "/BoxSize", "is not a cube: the group finders need one");
  in.box = box[0];
  in.time = header_scalar(f, "Time", 0.0, true);
  in.omega_m = header_scalar(f, "Omega0", 0.0, false);
  in.omega_lambda = header_scalar(f, "OmegaLambda", 0.0, false);
  in.hubble_param = header_scalar(f, "HubbleParam", 1.0, false);
  in.omega_b = header_scalar(f, "OmegaBaryon", -1.0, false);
  in.cosmological = in.omega_m > 0.0 && in.time > 0.0;
  if (f.exists("/Units")) {
    auto unit = [&](const char* name, double& out) {
      if (!f.has_attribute("/Units", name)) return;
      const std::vector<double> v = f.read_attribute_doubles("/Units", name);
      if (v.empty() || !(v[0] > 0.0)) f.fail(std::string("/Units/") + name, "is not a positive number");
      out = v[0];
    };
    unit("UnitLength_in_cm", in.units.length_cgs);
    unit("UnitMass_in_g", in.units.mass_cgs);
    unit("UnitVelocity_in_cm_per_s", in.units.velocity_cgs);
  }
  const std::vector<std::uint64_t> counts = f.read_attribute_uint64(kHeader, "NumPart_ThisFile");
  const std::vector<double> mass_table =
      f.has_attribute(kHeader, "MassTable") ? f.read_attribute_doubles(kHeader, "MassTable") : std::vector<double>(6, 0.0);
  if (counts.size() != 6 || mass_table.size() != 6) f.fail(kHeader, "NumPart_ThisFile and MassTable need 6 entries");
  // GADGET's cosmological velocities are v_pec / sqrt(a).
  const double to_peculiar = in.cosmological ? std::sqrt(in.time) : 1.0;
  for (int t = 0; t < 6; ++t) {
    const std::uint64_t n = counts[static_cast<std::size_t>(t)];
    if (n == 0) continue;
    const std::string group = fmt::format("/PartType{}", t);
    auto check = [&](const std::string& dataset, std::size_t size) {
      if (size != n) f.fail(dataset, fmt::format("has {} entries but NumPart_ThisFile[{}] is {}", size, t, n));
    };
    const std::vector<Vec3> x = f.read_vec3(group + "/Coordinates");
    check(group + "/Coordinates", x.size());
    const std::vector<Vec3> v = f.read_vec3(group + "/Velocities");
    check(group + "/Velocities", v.size());
    const std::vector<std::uint64_t> ids = f.read_uint64(group + "/ParticleIDs");
    check(group + "/ParticleIDs", ids.size());
    std::vector<double> m;
    if (f.exists(group + "/Masses")) {
      m = f.read_doubles(group + "/Masses");
      check(group + "/Masses", m.size());
    } else {
      if (!(mass_table[static_cast<std::size_t>(t)] > 0.0))
        f.fail(group + "/Masses", "is missing and MassTable gives no mass for the type");
      m.assign(n, mass_table[static_cast<std::size_t>(t)]);
    }
    std::vector<double> hidden(n, 0.0);
    if (t == 0 && f.exists(group + "/HiddenStellarMasses")) {
      hidden = f.read_doubles(group + "/HiddenStellarMasses");
      check(group + "/HiddenStellarMasses", hidden.size());
    }
    for (std::size_t k = 0; k < n; ++k) {
      if (!std::isfinite(x[k].x) || !std::isfinite(x[k].y) || !std::isfinite(x[k].z))
        f.fail(group + "/Coordinates", fmt::format("particle ID {} has a non-finite position", ids[k]));
      if (!(m[k] >= 0.0) || !std::isfinite(m[k]))
        f.fail(group + "/Masses", fmt::format("particle ID {} has mass {}", ids[k], m[k]));
      in.particles.push_back(x[k], v[k] * to_peculiar, m[k], ids[k], t);
      in.hidden_mass.push_back(hidden[k]);
    }
  }
  return in;
}

void write_fof_catalogue(const std::string& path, const groups::GroupCatalogue& catalogue, const GroupInput& input,
                         const FofCatalogueInfo& info) {
  hdf5::File f(path, hdf5::File::Mode::create);
  const std::vector<groups::Group>& groups = catalogue.groups;
  const std::size_t n = groups.size();
  std::vector<std::uint64_t> len(n), offset(n), len_type(6 * n), ids, types;
  std::vector<double> mass(n), mass_type(6 * n), m200(n), r200(n);
  std::vector<Vec3> cm(n), pos(n), vel(n);
  std::vector<std::int32_t> member_type;
  for (std::size_t g = 0; g < n; ++g) {
    const groups::Group& group = groups[g];
    len[g] = group.members.size();
    offset[g] = ids.size();
    for (int t = 0; t < 6; ++t) {
      len_type[6 * g + static_cast<std::size_t>(t)] = group.count_by_type[static_cast<std::size_t>(t)];
      mass_type[6 * g + static_cast<std::size_t>(t)] = group.mass_by_type[static_cast<std::size_t>(t)];
    }
    mass[g] = group.mass;
    m200[g] = group.m200;
    r200[g] = group.r200;
    cm[g] = group.centre_of_mass;
    pos[g] = group.potential_minimum;
    vel[g] = group.velocity;
    for (std::uint32_t i : group.members) {
      ids.push_back(catalogue.member_id[i]);
      member_type.push_back(catalogue.member_type[i]);
    }
  }
  write_catalogue_header(f, n, ids.size(), input, info.snapshot);
  f.write_attribute(kHeader, "LinkingLength", info.linking_length);
  f.write_attribute(kHeader, "LinkingLengthFactor", info.b);
  f.write_attribute(kHeader, "MinimumMembers", static_cast<std::int64_t>(info.min_members));
  f.write_attribute(kHeader, "LinkingTypes", std::vector<std::int32_t>(info.linking_types.begin(), info.linking_types.end()));
  f.write_attribute(kHeader, "Crit200Density", info.overdensity);
  f.write_attribute(kHeader, "Units",
                    "the snapshot's: lengths comoving (its length unit, per h in cosmological runs), masses in its "
                    "mass unit, velocities peculiar in its velocity unit; Crit200Density comoving");
  f.create_group("/Group");
  f.write_dataset("/Group/GroupLen", len, {{"Description", "Members of each group, all types"}});
  f.write_table("/Group/GroupLenType", len_type, 6, {{"Description", "Members of each group by particle type"}});
  f.write_dataset("/Group/GroupOffset", offset, {{"Description", "Index of each group's first member in /IDs"}});
  f.write_dataset("/Group/GroupMass", mass, {{"Description", "Mass of each group's members"}});
  f.write_table("/Group/GroupMassType", mass_type, 6, {{"Description", "Mass of each group's members by type"}});
  f.write_dataset("/Group/GroupCM", cm, {{"Description", "Centre of mass (periodic, folded into the box)"}});
  f.write_dataset("/Group/GroupPos", pos, {{"Description", "Position of the member of least potential (the group's own)"}});
  f.write_dataset("/Group/GroupVel", vel, {{"Description", "Mass-weighted mean peculiar velocity"}});
  f.write_dataset("/Group/Group_M_Crit200", m200,
                  {{"Description", "Mass of all particles within R_200 of GroupPos (mean density 200 rho_crit(z))"}});
  f.write_dataset("/Group/Group_R_Crit200", r200, {{"Description", "R_200 about GroupPos, comoving"}});
  f.create_group("/IDs");
  f.write_dataset("/IDs/ID", ids, {{"Description", "Member IDs, group by group (by type, then ID)"}});
  f.write_dataset("/IDs/Type", member_type, {{"Description", "GADGET particle type of each member"}});
}

FofHalos read_fof_halos(const std::string& path) {
  const hdf5::File f(path, hdf5::File::Mode::read);
  FofHalos h;
  h.box = header_scalar(f, "BoxSize", 0.0, true);
  h.time = header_scalar(f, "Time", 0.0, true);
  h.omega_m = header_scalar(f, "Omega0", 0.0, false);
  h.omega_lambda = header_scalar(f, "OmegaLambda", 0.0, false);
  h.hubble_param = header_scalar(f, "HubbleParam", 1.0, false);
  h.omega_b = header_scalar(f, "OmegaBaryon", -1.0, false);
  h.units.length_cgs = header_scalar(f, "UnitLength_in_cm", h.units.length_cgs, false);
  h.units.mass_cgs = header_scalar(f, "UnitMass_in_g", h.units.mass_cgs, false);
  h.units.velocity_cgs = header_scalar(f, "UnitVelocity_in_cm_per_s", h.units.velocity_cgs, false);
  h.centre = f.read_vec3("/Group/GroupPos");
  h.mass = f.read_doubles("/Group/GroupMass");
  h.m200 = f.read_doubles("/Group/Group_M_Crit200");
  h.r200 = f.read_doubles("/Group/Group_R_Crit200");
  if (h.m200.size() != h.centre.size() || h.r200.size() != h.centre.size() || h.mass.size() != h.centre.size())
    f.fail("/Group", "GroupPos, GroupMass, Group_M_Crit200 and Group_R_Crit200 differ in length");
  return h;
}

void write_hop_catalogue(const std::string& path, const groups::HopCatalogue& catalogue, const GroupInput& input,
                         const HopCatalogueInfo& info) {
  hdf5::File f(path, hdf5::File::Mode::create);
  const std::size_t n = catalogue.groups.size();
  std::vector<std::uint64_t> len(n), offset(n), len_type(6 * n), ids;
  std::vector<double> mass(n), mass_type(6 * n), peak_density(n), density;
  std::vector<Vec3> cm(n), peak(n), vel(n);
  std::vector<std::int32_t> member_type;
  for (std::size_t g = 0; g < n; ++g) {
    const groups::HopCatalogueGroup& group = catalogue.groups[g];
    len[g] = group.members.size();
    offset[g] = ids.size();
    for (std::size_t t = 0; t < 6; ++t) {
      len_type[6 * g + t] = group.count_by_type[t];
      mass_type[6 * g + t] = group.mass_by_type[t];
    }
    for (std::uint32_t m : group.members) {
      ids.push_back(catalogue.member_id[m]);
      member_type.push_back(catalogue.member_type[m]);
      density.push_back(catalogue.member_density[m]);
    }
    mass[g] = group.mass;
    cm[g] = group.centre_of_mass;
    peak[g] = group.peak;
    peak_density[g] = group.peak_density;
    vel[g] = group.velocity;
  }
  const groups::HopParameters& p = info.parameters;
  write_catalogue_header(f, n, ids.size(), input, info.snapshot);
  f.write_attribute(kHeader, "NDens", static_cast<std::int64_t>(p.n_dens));
  f.write_attribute(kHeader, "NHop", static_cast<std::int64_t>(p.n_hop));
  f.write_attribute(kHeader, "NMerge", static_cast<std::int64_t>(p.n_merge));
  f.write_attribute(kHeader, "DeltaOuter", p.delta_outer);
  f.write_attribute(kHeader, "DeltaSaddle", p.delta_saddle);
  f.write_attribute(kHeader, "DeltaPeak", p.delta_peak);
  f.write_attribute(kHeader, "MeanBaryonDensity", info.mean_baryon_density);
  f.write_attribute(kHeader, "MinimumMembers", static_cast<std::int64_t>(p.min_members));
  f.write_attribute(kHeader, "Units",
                    "the snapshot's: lengths comoving, masses in its mass unit, velocities peculiar; densities "
                    "comoving, mass per comoving volume");
  f.create_group("/Group");
  f.write_dataset("/Group/GroupLen", len, {{"Description", "Members of each group (gas and stars)"}});
  f.write_table("/Group/GroupLenType", len_type, 6, {{"Description", "Members of each group by particle type"}});
  f.write_dataset("/Group/GroupOffset", offset, {{"Description", "Index of each group's first member in /IDs"}});
  f.write_dataset("/Group/GroupMass", mass, {{"Description", "Baryonic mass: gas, its hidden stars, and stars"}});
  f.write_table("/Group/GroupMassType", mass_type, 6,
                {{"Description", "Mass by type: gas under 0, stars and the gas's hidden stellar mass under 4"}});
  f.write_dataset("/Group/GroupCM", cm, {{"Description", "Centre of mass (periodic, folded into the box)"}});
  f.write_dataset("/Group/GroupPeakPos", peak, {{"Description", "Position of the densest member"}});
  f.write_dataset("/Group/GroupPeakDensity", peak_density, {{"Description", "HOP density of the densest member"}});
  f.write_dataset("/Group/GroupVel", vel, {{"Description", "Mass-weighted mean peculiar velocity"}});
  f.create_group("/IDs");
  f.write_dataset("/IDs/ID", ids, {{"Description", "Member IDs, group by group"}});
  f.write_dataset("/IDs/Type", member_type, {{"Description", "GADGET particle type of each member"}});
  f.write_dataset("/IDs/Density", density, {{"Description", "HOP density of each member"}});
}

}  // namespace fountain::io
