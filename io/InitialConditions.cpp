#include "io/InitialConditions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numeric>
#include <span>
#include <string>
#include <system_error>
#include <vector>

#include "core/Error.hpp"
#include "io/GadgetBinary.hpp"
#include "io/Hdf5File.hpp"

namespace fountain::io {

namespace {

using hdf5::File;

constexpr const char* kHeader = "/Header";
constexpr const char* kGas = "/PartType0";
constexpr const char* kDarkMatter = "/PartType1";

// One particle type of the GADGET layout: its index in the /Header arrays, its group and
// what the messages call it. The readers below are written once for every type.
struct Species {
  int type;
  const char* group;
  const char* noun;
  std::string dataset(const char* name) const { return std::string(group) + "/" + name; }
};
constexpr Species kGasSpecies{0, kGas, "gas"};
constexpr Species kDarkMatterSpecies{1, kDarkMatter, "dark matter"};
constexpr Species kType2{2, "/PartType2", "low-resolution dark matter (type 2)"};
constexpr Species kType3{3, "/PartType3", "low-resolution dark matter (type 3)"};
constexpr Species kType5{5, "/PartType5", "low-resolution dark matter (type 5)"};

// Checks that `dataset` has n rows (and 3 columns when `vector` is set) before reading it.
void check_shape(const File& file, const Species& sp, const std::string& dataset, std::uint64_t n, bool vector) {
  const hdf5::DatasetInfo info = file.dataset_info(dataset);
  const std::size_t want_rank = vector ? 2 : 1;
  if (info.dims.size() != want_rank || (vector && info.dims[1] != 3)) {
    std::string shape;
    for (std::size_t d = 0; d < info.dims.size(); ++d) shape += (d ? " x " : "") + std::to_string(info.dims[d]);
    file.fail(dataset, fmt::format("has shape ({}), expected {}", shape, vector ? "N x 3" : "N"));
  }
  if (info.dims[0] != n)
    file.fail(dataset, fmt::format("has {} entries but /Header/NumPart_ThisFile[{}] announces {} {} particles",
                                   info.dims[0], sp.type, n, sp.noun));
}

// The ParticleIDs of one type (of `rows` only, with it); an ID that appears twice within the
// type is an error, checked over every row where `check_all` is set.
std::vector<std::uint64_t> read_ids(const File& file, const Species& sp, std::uint64_t n,
                                    const hdf5::RowRange* rows = nullptr, bool check_all = true,
                                    std::vector<std::uint64_t>* all_ids = nullptr) {
  const std::string dataset = sp.dataset("ParticleIDs");
  if (!file.exists(dataset)) file.fail(dataset, "dataset not found");
  check_shape(file, sp, dataset, n, false);
  if (!check_all) return file.read_uint64(dataset, rows);
  std::vector<std::uint64_t> ids = file.read_uint64(dataset);
  std::vector<std::size_t> order(ids.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return ids[a] != ids[b] ? ids[a] < ids[b] : a < b; });
  for (std::size_t k = 1; k < order.size(); ++k)
    if (ids[order[k]] == ids[order[k - 1]])
      file.fail(dataset, fmt::format("particle ID {} appears more than once (entries {} and {}); IDs must be unique",
                                     ids[order[k]], order[k - 1], order[k]));
  std::vector<std::uint64_t> out = rows == nullptr ? ids
                                                  : std::vector<std::uint64_t>(
                                                        ids.begin() + static_cast<std::ptrdiff_t>(rows->first),
                                                        ids.begin() + static_cast<std::ptrdiff_t>(rows->first + rows->count));
  if (all_ids) *all_ids = std::move(ids);
  return out;
}

std::vector<Vec3> read_vectors(const File& file, const Species& sp, const char* name, std::uint64_t n,
                               const std::vector<std::uint64_t>& ids, const char* what,
                               const hdf5::RowRange* rows = nullptr) {
  const std::string dataset = sp.dataset(name);
  if (!file.exists(dataset)) file.fail(dataset, "dataset not found");
  check_shape(file, sp, dataset, n, true);
  std::vector<Vec3> values = file.read_vec3(dataset, rows);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const Vec3& v = values[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      file.fail(dataset, fmt::format("particle ID {} has non-finite {} ({}, {}, {})", ids[i], what, v.x, v.y, v.z));
  }
  return values;
}

std::vector<double> read_scalars(const File& file, const Species& sp, const char* name, std::uint64_t n,
                                 const hdf5::RowRange* rows = nullptr) {
  const std::string dataset = sp.dataset(name);
  check_shape(file, sp, dataset, n, false);
  return file.read_doubles(dataset, rows);
}

// The Masses dataset, or else the type's /Header/MassTable entry; every mass must be positive.
std::vector<double> read_masses(const File& file, const Species& sp, std::uint64_t n,
                                const std::vector<std::uint64_t>& ids, const std::vector<double>* mass_table,
                                const hdf5::RowRange* rows = nullptr) {
  const std::string dataset = sp.dataset("Masses");
  if (file.exists(dataset)) {
    std::vector<double> mass = read_scalars(file, sp, "Masses", n, rows);
    for (std::size_t i = 0; i < mass.size(); ++i)
      if (!std::isfinite(mass[i]) || mass[i] <= 0.0)
        file.fail(dataset, fmt::format("particle ID {} has mass {} (must be positive)", ids[i], mass[i]));
    return mass;
  }
  const auto t = static_cast<std::size_t>(sp.type);
  if (mass_table == nullptr)
    file.fail(dataset, fmt::format("dataset not found and /Header has no MassTable: the {} masses are missing", sp.noun));
  if (mass_table->size() <= t)
    file.fail(dataset, fmt::format("dataset not found and /Header/MassTable has no entry {}: the {} masses are missing",
                                   sp.type, sp.noun));
  const double table_mass = (*mass_table)[t];
  if (table_mass == 0.0)
    file.fail(dataset, fmt::format("dataset not found and /Header/MassTable[{}] is 0: the {} masses are missing",
                                   sp.type, sp.noun));
  if (!std::isfinite(table_mass) || table_mass < 0.0)
    file.fail("/Header/MassTable", fmt::format("entry {} ({}) is {} (must be positive)", sp.type, sp.noun, table_mass));
  return std::vector<double>(rows ? rows->count : n, table_mass);
}

// NumPart_ThisFile[type] (0 where the array is shorter), checked against NumPart_Total (with
// its high word) when the file has one.
std::uint64_t particle_count(const File& file, const std::vector<std::uint64_t>& this_file, const Species& sp) {
  const auto t = static_cast<std::size_t>(sp.type);
  const std::uint64_t n = t < this_file.size() ? this_file[t] : 0;
  if (file.has_attribute(kHeader, "NumPart_Total")) {
    const std::vector<std::uint64_t> total = file.read_attribute_uint64(kHeader, "NumPart_Total");
    std::uint64_t high = 0;
    if (file.has_attribute(kHeader, "NumPart_Total_HighWord")) {
      const std::vector<std::uint64_t> hw = file.read_attribute_uint64(kHeader, "NumPart_Total_HighWord");
      if (t < hw.size()) high = hw[t];
    }
    if (t < total.size()) {
      const std::uint64_t n_total = total[t] + (high << 32);
      if (n_total != n)
        file.fail("/Header/NumPart_Total", fmt::format("announces {} {} particles but NumPart_ThisFile[{}] is {}",
                                                       n_total, sp.noun, sp.type, n));
    }
  }
  return n;
}

// Reads the collisionless particles of one GADGET type (none when NumPart_ThisFile says 0).
// With `rows`, of those rows only; IDs are checked for repeats (and handed back whole in
// `all_ids`) where `check_all` is set.
CollisionlessParticles read_collisionless(const File& file, const Species& sp, std::uint64_t n,
                                          const std::vector<double>* mass_table, fountain::Species species,
                                          const hdf5::RowRange* rows = nullptr, bool check_all = true,
                                          std::vector<std::uint64_t>* all_ids = nullptr) {
  CollisionlessParticles dm;
  if (n == 0) return dm;
  if (!file.exists(sp.group))
    file.fail(sp.group, fmt::format("group not found, but /Header/NumPart_ThisFile[{}] announces {} {} particles",
                                    sp.type, n, sp.noun));
  const std::vector<std::uint64_t> ids = read_ids(file, sp, n, rows, check_all, all_ids);
  const std::vector<Vec3> x = read_vectors(file, sp, "Coordinates", n, ids, "coordinates", rows);
  const std::vector<Vec3> v = read_vectors(file, sp, "Velocities", n, ids, "velocity", rows);
  const std::vector<double> mass = read_masses(file, sp, n, ids, mass_table, rows);
  dm.resize(ids.size());  // a_grav, potential, time_bin and ti_begin start at zero
  dm.id = ids;
  dm.species.assign(ids.size(), species);
  dm.mass = mass;
  dm.x = x;
  dm.v_full = v;
  dm.v = v;
  return dm;
}

void append(CollisionlessParticles& to, const CollisionlessParticles& from) {
  const std::size_t n = to.size();
  to.resize(n + from.size());
  for (std::size_t i = 0; i < from.size(); ++i) {
    to.id[n + i] = from.id[i];
    to.species[n + i] = from.species[i];
    to.mass[n + i] = from.mass[i];
    to.x[n + i] = from.x[i];
    to.v_full[n + i] = from.v_full[i];
    to.v[n + i] = from.v[i];
  }
}

// IDs must be unique across the types: names the first collisionless particle whose ID a gas
// particle or an earlier collisionless particle also uses. `ids_of(species)` names where the
// file holds that species' IDs.
template <class IdsOf>
void check_ids_across_species(const std::string& path, const std::vector<std::uint64_t>& gas_id,
                              const std::vector<std::uint64_t>& dm_id, const std::vector<fountain::Species>& dm_species,
                              IdsOf&& ids_of) {
  if (dm_id.empty()) return;
  std::vector<std::uint64_t> gas_ids(gas_id);
  std::sort(gas_ids.begin(), gas_ids.end());
  for (std::size_t i = 0; i < dm_id.size(); ++i)
    if (std::binary_search(gas_ids.begin(), gas_ids.end(), dm_id[i]))
      throw InputError(fmt::format("{}: {}: particle ID {} ({}) is also used by a gas particle; IDs must be unique "
                                   "across gas and dark matter",
                                   path, ids_of(dm_species[i]), dm_id[i], species_name(dm_species[i])));
  std::vector<std::size_t> order(dm_id.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return dm_id[a] != dm_id[b] ? dm_id[a] < dm_id[b] : a < b; });
  for (std::size_t k = 1; k < order.size(); ++k)
    if (dm_id[order[k]] == dm_id[order[k - 1]])
      throw InputError(fmt::format("{}: {}: particle ID {} is used by both a {} and a {} particle; IDs must be "
                                   "unique across the particle types",
                                   path, ids_of(dm_species[order[k]]), dm_id[order[k]],
                                   species_name(dm_species[order[k - 1]]), species_name(dm_species[order[k]])));
}

// The header's cosmology and the /Units group's unit system, where the file gives them.
void read_file_cosmology(const File& file, InitialConditions& ic) {
  auto scalar = [&](const char* object, const char* name, double& out) {
    if (!file.has_attribute(object, name)) return false;
    const std::vector<double> v = file.read_attribute_doubles(object, name);
    if (v.empty() || !std::isfinite(v[0]))
      file.fail(std::string(object) + "/" + name, "is empty or not finite");
    out = v[0];
    return true;
  };
  IcFileCosmology& c = ic.cosmology;
  c.present = scalar(kHeader, "Omega0", c.omega0) & scalar(kHeader, "OmegaLambda", c.omega_lambda) &
              scalar(kHeader, "HubbleParam", c.hubble_param);
  scalar(kHeader, "Redshift", c.redshift);
  if (file.exists("/Units")) {
    scalar("/Units", "UnitLength_in_cm", ic.units.length_cgs);
    scalar("/Units", "UnitMass_in_g", ic.units.mass_cgs);
    scalar("/Units", "UnitVelocity_in_cm_per_s", ic.units.velocity_cgs);
  }
}

// Positive, finite internal energies, or (cosmological files) none at all: 0 is "not given".
void check_internal_energies(const std::string& where, const std::vector<std::uint64_t>& ids,
                             const std::vector<double>& u, bool cosmological, bool& given) {
  given = !u.empty();
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (cosmological && u[i] == 0.0) {
      given = false;
      continue;
    }
    if (!std::isfinite(u[i]) || u[i] <= 0.0)
      throw InputError(fmt::format("{}: particle ID {} has internal energy {} (must be positive and finite)", where,
                                   ids[i], u[i]));
  }
  if (cosmological && !given)
    for (double v : u)
      if (v != 0.0)
        throw InputError(fmt::format("{}: some gas particles have an internal energy and some have 0; give all or "
                                     "none",
                                     where));
}

// The rows one rank of options.share_ranks reads of a file's n gas (or collisionless) particles.
hdf5::RowRange gas_share(std::uint64_t n, const IcReadOptions& options) {
  const auto r = static_cast<std::uint64_t>(options.share_rank), ranks = static_cast<std::uint64_t>(options.share_ranks);
  const std::uint64_t first = n * r / ranks;
  return {first, n * (r + 1) / ranks - first};
}

// A GADGET binary file (format 1 or 2) as initial conditions.
InitialConditions read_gadget_binary_ics(const std::string& path, const IcReadOptions& options) {
  const GadgetSnapshot snap = read_gadget_binary(path);
  const GadgetHeader& h = snap.header;
  InitialConditions ic;
  ic.format = "GADGET binary";
  ic.box_size = {h.box_size, h.box_size, h.box_size};
  ic.time = h.time;
  ic.cosmology = {true, h.omega0, h.omega_lambda, h.hubble_param, h.redshift};
  if (h.flag_entropy_ics != 0)
    throw InputError(fmt::format("{}: flag_entropy_instead_u is set: the U block holds entropy, which is not "
                                 "supported; write the specific internal energy instead",
                                 path));
  const GadgetParticles& g = snap.types[0];
  const std::size_t n = g.id.size();
  if (n == 0 && !options.cosmological)
    throw InputError(fmt::format("{}: has no gas particles (type 0); Fountain needs gas particles", path));
  for (int t : {1, 4})
    if (!snap.types[static_cast<std::size_t>(t)].id.empty() && t == 4)
      throw InputError(fmt::format("{}: holds star particles (type 4), which initial conditions cannot have", path));
  std::vector<double> u = g.u;
  if (u.empty() && !options.cosmological)
    throw InputError(fmt::format("{}: has no U block (the gas needs a specific internal energy)", path));
  check_internal_energies(path + " (block U)", g.id, u, options.cosmological, ic.has_internal_energy);
  if (!ic.has_internal_energy) u.assign(n, 0.0);
  GasParticles& gas = ic.gas;
  gas.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    gas.id[i] = g.id[i];
    gas.mass[i] = g.mass[i];
    gas.x[i] = gas.x[i] = g.x[i];
    gas.v_full[i] = gas.v[i] = g.v[i];
    gas.u_full[i] = gas.u[i] = u[i];
    gas.h[i] = 0.0;
    gas.time_bin[i] = 0;
  }
  for (int t : {1, 2, 3, 5}) {
    const GadgetParticles& p = snap.types[static_cast<std::size_t>(t)];
    if (p.id.empty()) continue;
    if (t != 1 && !options.cosmological)
      throw InputError(fmt::format("{}: holds {} particles of type {}, which only comoving runs read", path,
                                   p.id.size(), t));
    CollisionlessParticles part;
    part.resize(p.id.size());
    part.id = p.id;
    part.species.assign(p.id.size(), t == 1 ? fountain::Species::DarkMatter : fountain::Species::LowResDarkMatter);
    part.mass = p.mass;
    part.x = p.x;
    part.v_full = part.v = p.v;
    append(ic.dm, part);
  }
  if (ic.gas.size() + ic.dm.size() == 0) throw InputError(fmt::format("{}: holds no particles", path));
  check_ids_across_species(path, ic.gas.id, ic.dm.id, ic.dm.species, [](fountain::Species) { return "block ID"; });
  ic.gas_total = n;
  ic.dm_total = ic.dm.size();
  if (options.share_ranks > 1) {
    const hdf5::RowRange rows = gas_share(n, options);
    std::vector<std::size_t> keep(rows.count);
    std::iota(keep.begin(), keep.end(), static_cast<std::size_t>(rows.first));
    ic.gas.permute(keep);
    ic.gas_first = rows.first;
    const hdf5::RowRange dm_rows = gas_share(ic.dm_total, options);
    keep.resize(dm_rows.count);
    std::iota(keep.begin(), keep.end(), static_cast<std::size_t>(dm_rows.first));
    ic.dm.permute(keep);
    ic.dm_first = dm_rows.first;
  }
  return ic;
}

}  // namespace

InitialConditions read_initial_conditions(const std::string& path, const IcReadOptions& options) {
  if (options.share_ranks < 1 || options.share_rank < 0 || options.share_rank >= options.share_ranks)
    throw std::logic_error(fmt::format("initial conditions asked for share {} of {}", options.share_rank, options.share_ranks));
  namespace fs = std::filesystem;
  std::error_code ec;
  // A GADGET binary set split over files is named without its ".0".
  if (!fs::exists(path, ec) && fs::exists(path + ".0", ec) && is_gadget_binary(path))
    return read_gadget_binary_ics(path, options);
  if (!fs::exists(path, ec)) throw InputError(path + ": initial conditions file not found");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, not an HDF5 initial conditions file");
  if (!hdf5::is_hdf5(path)) {
    if (is_gadget_binary(path)) return read_gadget_binary_ics(path, options);
    throw InputError(path + ": not an HDF5 file, nor GADGET binary (expected GADGET-layout initial conditions)");
  }

  const File file(path, File::Mode::read);
  if (!file.exists(kHeader)) file.fail(kHeader, "group not found (not a GADGET-layout HDF5 file?)");

  // --- Header ---------------------------------------------------------------------------
  const std::vector<std::uint64_t> this_file = file.read_attribute_uint64(kHeader, "NumPart_ThisFile");
  if (this_file.empty()) file.fail("/Header/NumPart_ThisFile", "is empty");

  if (file.has_attribute(kHeader, "NumFilesPerSnapshot")) {
    const std::vector<std::uint64_t> files = file.read_attribute_uint64(kHeader, "NumFilesPerSnapshot");
    if (!files.empty() && files[0] > 1)
      file.fail("/Header/NumFilesPerSnapshot",
                fmt::format("is {}: initial conditions split over several files are not supported; "
                            "combine them into one file",
                            files[0]));
  }
  const std::uint64_t n = particle_count(file, this_file, kGasSpecies);
  const std::uint64_t n_dm = particle_count(file, this_file, kDarkMatterSpecies);
  if (n == 0 && !options.cosmological)
    file.fail("/Header/NumPart_ThisFile",
              n_dm == 0 ? std::string("has no gas particles (entry 0 is 0); Fountain needs gas particles in /PartType0")
                        : fmt::format("has no gas particles (entry 0 is 0, entry 1 announces {} dark matter "
                                      "particles); Fountain needs gas particles in /PartType0",
                                      n_dm));

  if (file.has_attribute(kHeader, "Flag_Entropy_ICs")) {
    for (double flag : file.read_attribute_doubles(kHeader, "Flag_Entropy_ICs"))
      if (flag != 0.0)
        file.fail("/Header/Flag_Entropy_ICs",
                  "is set: InternalEnergy holds entropy, which is not supported; write the specific internal "
                  "energy instead");
  }

  InitialConditions ic;
  read_file_cosmology(file, ic);

  if (!file.has_attribute(kHeader, "BoxSize")) file.fail(kHeader, "attribute BoxSize not found");
  const std::vector<double> box = file.read_attribute_doubles(kHeader, "BoxSize");
  if (box.size() == 1) {
    ic.box_size = {box[0], box[0], box[0]};
  } else if (box.size() == 3) {
    ic.box_size = {box[0], box[1], box[2]};
  } else {
    file.fail("/Header/BoxSize", fmt::format("has {} values, expected 1 or 3", box.size()));
  }
  for (double b : box)
    if (!std::isfinite(b) || b < 0.0)
      file.fail("/Header/BoxSize", fmt::format("holds {} (must be finite and non-negative)", b));

  if (file.has_attribute(kHeader, "Time")) {
    ic.time = file.read_attribute_double(kHeader, "Time");
    if (!std::isfinite(ic.time)) file.fail("/Header/Time", fmt::format("is {} (must be finite)", ic.time));
  }

  std::vector<double> mass_table;
  const bool has_mass_table = file.has_attribute(kHeader, "MassTable");
  if (has_mass_table) {
    mass_table = file.read_attribute_doubles(kHeader, "MassTable");
    if (mass_table.empty()) file.fail("/Header/MassTable", "is empty");
  }
  const std::vector<double>* table = has_mass_table ? &mass_table : nullptr;

  // --- Gas particles ------------------------------------------------------------------
  // (none in a cosmological run of dark matter alone)
  const bool shared = options.share_ranks > 1;
  const bool checks_ids = !shared || options.share_rank == 0;  // the share that checks every ID
  std::vector<std::uint64_t> all_gas_ids;  // a share's check: every gas ID
  if (n > 0) {
    const Species& sp = kGasSpecies;
    if (!file.exists(kGas))
      file.fail(kGas, fmt::format("group not found, but /Header/NumPart_ThisFile[0] announces {} gas particles", n));

    // A share's rows only (all of them without one).
    const hdf5::RowRange share = gas_share(n, options);
    const hdf5::RowRange* rows = options.share_ranks > 1 ? &share : nullptr;
    const std::vector<std::uint64_t> ids = read_ids(file, sp, n, rows, checks_ids, shared ? &all_gas_ids : nullptr);
    const std::vector<Vec3> x = read_vectors(file, sp, "Coordinates", n, ids, "coordinates", rows);
    const std::vector<Vec3> v = read_vectors(file, sp, "Velocities", n, ids, "velocity", rows);
    const std::vector<double> mass = read_masses(file, sp, n, ids, table, rows);
    ic.gas_first = share.first;
    const std::size_t count = ids.size();

    const std::string u_name = kGasSpecies.dataset("InternalEnergy");
    std::vector<double> u;
    if (file.exists(u_name)) {
      u = read_scalars(file, sp, "InternalEnergy", n, rows);
    } else if (n > 0 && !options.cosmological) {
      file.fail(u_name, "dataset not found (the gas needs a specific internal energy)");
    }
    check_internal_energies(path + ": " + u_name, ids, u, options.cosmological, ic.has_internal_energy);
    if (!ic.has_internal_energy) u.assign(count, 0.0);

    std::vector<double> h;
    const std::string h_name = kGasSpecies.dataset("SmoothingLength");
    ic.has_smoothing_length = file.exists(h_name);
    if (ic.has_smoothing_length) {
      h = read_scalars(file, sp, "SmoothingLength", n, rows);
      for (std::size_t i = 0; i < h.size(); ++i)
        if (!std::isfinite(h[i]) || h[i] < 0.0)
          file.fail(h_name, fmt::format("particle ID {} has smoothing length {} (must be finite and non-negative)",
                                        ids[i], h[i]));
    } else {
      h.assign(count, 0.0);
    }

    // --- Fill the particles ---------------------------------------------------------------
    GasParticles& gas = ic.gas;
    gas.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      gas.id[i] = ids[i];
      gas.mass[i] = mass[i];
      gas.x[i] = x[i];
      gas.v_full[i] = v[i];
      gas.v[i] = v[i];
      gas.u_full[i] = u[i];
      gas.u[i] = u[i];
      gas.h[i] = h[i];
      gas.time_bin[i] = 0;
    }

  }

  ic.gas_total = n;

  // --- Dark matter, and a cosmological file's coarser types after it ----------------------
  struct Part {
    const Species* sp;
    std::uint64_t n;
    fountain::Species species;
  };
  std::vector<Part> parts{{&kDarkMatterSpecies, n_dm, fountain::Species::DarkMatter}};
  if (options.cosmological)
    for (const Species* low : {&kType2, &kType3, &kType5})
      parts.push_back({low, particle_count(file, this_file, *low), fountain::Species::LowResDarkMatter});
  for (const Part& part : parts) ic.dm_total += part.n;
  // A share: the same rows of the types laid end to end, each type's part by hyperslab.
  const hdf5::RowRange dm_share = gas_share(ic.dm_total, options);
  ic.dm_first = shared ? dm_share.first : 0;
  std::vector<std::uint64_t> all_dm_ids;
  std::vector<fountain::Species> all_dm_species;
  std::uint64_t offset = 0;
  for (const Part& part : parts) {
    const std::uint64_t lo = std::clamp(dm_share.first, offset, offset + part.n);
    const std::uint64_t hi = std::clamp(dm_share.first + dm_share.count, offset, offset + part.n);
    const hdf5::RowRange rows{lo - offset, hi - lo};
    std::vector<std::uint64_t> ids;
    append(ic.dm, read_collisionless(file, *part.sp, part.n, table, part.species, shared ? &rows : nullptr, checks_ids,
                                     shared && checks_ids ? &ids : nullptr));
    all_dm_ids.insert(all_dm_ids.end(), ids.begin(), ids.end());
    all_dm_species.insert(all_dm_species.end(), ids.size(), part.species);
    offset += part.n;
  }
  if (n + ic.dm_total == 0) file.fail("/Header/NumPart_ThisFile", "announces no particles");
  auto where = [](fountain::Species s) {
    return s == fountain::Species::DarkMatter ? "/PartType1/ParticleIDs" : "/PartType2, 3 or 5/ParticleIDs";
  };
  if (!shared) check_ids_across_species(path, ic.gas.id, ic.dm.id, ic.dm.species, where);
  else if (checks_ids) check_ids_across_species(path, all_gas_ids, all_dm_ids, all_dm_species, where);
  return ic;
}

namespace {

// The fields a file holds, viewed where they lie in either store (a run's, or a generator's
// lean one), so that one writer serves both and copies neither.
struct GasFields {
  std::span<const std::uint64_t> id;
  std::span<const double> mass;
  std::span<const Vec3> x, v;  // v: the velocity the file's convention starts from
  std::span<const double> u, h;
};
struct CollisionlessFields {
  std::span<const std::uint64_t> id;
  std::span<const fountain::Species> species;
  std::span<const double> mass;
  std::span<const Vec3> x, v;
};

GasFields fields_of(const GasParticles& g) { return {g.id, g.mass, g.x, g.v_full, g.u_full, g.h}; }
GasFields fields_of(const IcGasParticles& g) { return {g.id, g.mass, g.x, g.v, g.u, g.h}; }
CollisionlessFields fields_of(const CollisionlessParticles& d) { return {d.id, d.species, d.mass, d.x, d.v_full}; }
CollisionlessFields fields_of(const IcCollisionlessParticles& d) { return {d.id, d.species, d.mass, d.x, d.v}; }

// The rows of one particle type in the file: all of a store's particles in order, or (a zoom's
// dark matter, split by resolution) the listed ones.
struct Rows {
  std::size_t count = 0;
  std::vector<std::size_t> members;  // empty: row r is particle r
  bool all() const { return members.empty(); }
  std::size_t operator[](std::size_t r) const { return all() ? r : members[r]; }
};

// Common mass of the rows, or 0 if they differ (for /Header/MassTable).
double common_mass(std::span<const double> mass, const Rows& rows) {
  if (rows.count == 0) return 0.0;
  const double first = mass[rows[0]];
  for (std::size_t r = 1; r < rows.count; ++r)
    if (mass[rows[r]] != first) return 0.0;
  return first;
}

// The smallest ID two particles share, gas and collisionless together (0 and false if none).
// Each type's IDs are read where they lie when they are in order already, as generators make
// them, else from a sorted copy: a large box's IDs are never copied.
bool shared_id(std::span<const std::uint64_t> a, std::span<const std::uint64_t> b, std::uint64_t& id) {
  std::vector<std::uint64_t> sorted_a, sorted_b;
  auto in_order = [](std::span<const std::uint64_t> ids, std::vector<std::uint64_t>& copy) {
    if (std::is_sorted(ids.begin(), ids.end())) return ids;
    copy.assign(ids.begin(), ids.end());
    std::sort(copy.begin(), copy.end());
    return std::span<const std::uint64_t>(copy);
  };
  a = in_order(a, sorted_a);
  b = in_order(b, sorted_b);
  bool found = false;
  auto note = [&](std::uint64_t candidate) {
    if (!found || candidate < id) id = candidate;
    found = true;
  };
  for (std::span<const std::uint64_t> ids : {a, b}) {
    const auto twice = std::adjacent_find(ids.begin(), ids.end());
    if (twice != ids.end()) note(*twice);
  }
  for (std::size_t i = 0, j = 0; i < a.size() && j < b.size();) {
    if (a[i] < b[j]) {
      ++i;
    } else if (b[j] < a[i]) {
      ++j;
    } else {
      note(a[i]);
      break;
    }
  }
  return found;
}

// The rows' vectors times `scale`, written straight from the store where nothing changes.
void write_vectors(File& file, const std::string& dataset, std::span<const Vec3> values, const Rows& rows,
                   double scale = 1.0) {
  if (rows.all() && scale == 1.0) return file.write_dataset(dataset, values);
  file.write_dataset_in_pieces(dataset, rows.count, 3, [&](std::size_t first, std::span<double> out) {
    for (std::size_t r = 0; 3 * r < out.size(); ++r) {
      const Vec3 v = values[rows[first + r]] * scale;
      out[3 * r] = v.x;
      out[3 * r + 1] = v.y;
      out[3 * r + 2] = v.z;
    }
  });
}

void write_scalars(File& file, const std::string& dataset, std::span<const double> values, const Rows& rows,
                   double scale = 1.0) {
  if (rows.all() && scale == 1.0) return file.write_dataset(dataset, values);
  file.write_dataset_in_pieces(dataset, rows.count, 1, [&](std::size_t first, std::span<double> out) {
    for (std::size_t r = 0; r < out.size(); ++r) out[r] = values[rows[first + r]] * scale;
  });
}

void write_ids(File& file, const std::string& dataset, std::span<const std::uint64_t> ids, const Rows& rows) {
  if (rows.all()) return file.write_dataset(dataset, ids);
  file.write_dataset_in_pieces(dataset, rows.count, [&](std::size_t first, std::span<std::uint64_t> out) {
    for (std::size_t r = 0; r < out.size(); ++r) out[r] = ids[rows[first + r]];
  });
}

void write_ic_file(const std::string& path, const GasFields& gas, const CollisionlessFields* dm,
                   const Vec3& box_size, bool periodic, double time, const CosmologicalIcInfo* cosmological = nullptr) {
  const std::size_t n = gas.id.size();
  const std::string prefix = "cannot create initial conditions " + path + ": ";
  if (n == 0 && (cosmological == nullptr || dm == nullptr || dm->id.empty()))
    throw InputError(prefix + "there are no gas particles to write");
  auto check = [&](std::size_t size, const char* field) {
    if (size != n) throw InputError(prefix + fmt::format("gas field {} has {} entries, expected {}", field, size, n));
  };
  check(gas.mass.size(), "mass");
  check(gas.x.size(), "x");
  check(gas.v.size(), "v_full");
  check(gas.u.size(), "u_full");
  check(gas.h.size(), "h");

  const std::size_t n_dm = dm != nullptr ? dm->id.size() : 0;
  if (dm != nullptr) {
    auto check_dm = [&](std::size_t size, const char* field) {
      if (size != n_dm)
        throw InputError(prefix + fmt::format("dark matter field {} has {} entries, expected {}", field, size, n_dm));
    };
    check_dm(dm->species.size(), "species");
    check_dm(dm->mass.size(), "mass");
    check_dm(dm->x.size(), "x");
    check_dm(dm->v.size(), "v_full");
    for (std::size_t i = 0; i < n_dm; ++i)
      if (!std::isfinite(dm->mass[i]) || dm->mass[i] <= 0.0)
        throw InputError(prefix + fmt::format("dark matter particle ID {} has mass {} (must be positive)", dm->id[i],
                                              dm->mass[i]));
    // IDs must be unique across both types.
    std::uint64_t twice = 0;
    if (shared_id(gas.id, dm->id, twice))
      throw InputError(prefix + fmt::format("particle ID {} is used more than once (IDs must be unique across gas "
                                            "and dark matter)",
                                            twice));
  }

  // A comoving run's files hold GADGET's velocities and physical energies (u = u' / a^2 for
  // gamma = 5/3, the only adiabatic index of comoving runs), scaled on the way to the file.
  const double a = cosmological != nullptr ? cosmological->a : 1.0;
  const double v_scale = cosmological != nullptr ? std::pow(a, -1.5) : 1.0;
  const double u_scale = cosmological != nullptr ? 1.0 / (a * a) : 1.0;
  // A zoom's low-resolution dark matter goes to /PartType2, the rest to /PartType1.
  Rows high, low;
  if (dm != nullptr) {
    for (fountain::Species s : dm->species) low.count += s == fountain::Species::LowResDarkMatter;
    high.count = n_dm - low.count;
    if (low.count > 0 && high.count > 0)
      for (std::size_t i = 0; i < n_dm; ++i)
        (dm->species[i] == fountain::Species::LowResDarkMatter ? low : high).members.push_back(i);
  }
  hdf5::write_file_atomically(path, "initial conditions", [&](File& file) {
    if (cosmological != nullptr) {
      hdf5::write_gadget_header(file, {n, high.count, low.count, 0, 0, 0}, {box_size.x}, a, &cosmological->cosmology);
      const Units& u = cosmological->units;
      file.create_group("/Units");
      file.write_attribute("/Units", "UnitLength_in_cm", u.length_cgs);
      file.write_attribute("/Units", "UnitMass_in_g", u.mass_cgs);
      file.write_attribute("/Units", "UnitVelocity_in_cm_per_s", u.velocity_cgs);
      if (!cosmological->generator_numbers.empty() || !cosmological->generator_integers.empty() ||
          !cosmological->generator_words.empty()) {
        file.create_group("/Cosmology");
        for (const auto& [name, value] : cosmological->generator_numbers) file.write_attribute("/Cosmology", name, value);
        for (const auto& [name, value] : cosmological->generator_integers) file.write_attribute("/Cosmology", name, value);
        for (const auto& [name, value] : cosmological->generator_words) file.write_attribute("/Cosmology", name, value);
      }
    } else {
      hdf5::write_gadget_header(file, {n, high.count, low.count, 0, 0, 0}, {box_size.x, box_size.y, box_size.z},
                                time);
    }
    // Not a GADGET field; records the boundary conditions the set-up was made for.
    file.write_attribute(kHeader, "Periodic", periodic ? 1 : 0);
    std::vector<double> table(6, 0.0);
    if (n > 0) {
      const Rows all{n, {}};
      file.create_group(kGas);
      file.write_dataset(kGasSpecies.dataset("Coordinates"), gas.x);
      write_vectors(file, kGasSpecies.dataset("Velocities"), gas.v, all, v_scale);
      file.write_dataset(kGasSpecies.dataset("ParticleIDs"), gas.id);
      file.write_dataset(kGasSpecies.dataset("Masses"), gas.mass);
      write_scalars(file, kGasSpecies.dataset("InternalEnergy"), gas.u, all, u_scale);
      file.write_dataset(kGasSpecies.dataset("SmoothingLength"), gas.h);
      table[0] = common_mass(gas.mass, all);
    }
    if (dm == nullptr) return;

    for (const Rows* rows : {&high, &low}) {
      if (rows->count == 0) continue;
      // Each type's common mass in the table (the header as written above has zeros).
      const Species& sp = rows == &low ? kType2 : kDarkMatterSpecies;
      table[static_cast<std::size_t>(sp.type)] = common_mass(dm->mass, *rows);
      file.create_group(sp.group);
      write_vectors(file, sp.dataset("Coordinates"), dm->x, *rows);
      write_vectors(file, sp.dataset("Velocities"), dm->v, *rows, v_scale);
      write_ids(file, sp.dataset("ParticleIDs"), dm->id, *rows);
      write_scalars(file, sp.dataset("Masses"), dm->mass, *rows);
    }
    file.write_attribute(kHeader, "MassTable", table);
  });
}

}  // namespace

void write_initial_conditions(const std::string& path, const GasParticles& gas, const Vec3& box_size,
                              bool periodic, double time) {
  write_ic_file(path, fields_of(gas), nullptr, box_size, periodic, time);
}

void write_initial_conditions(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                              const Vec3& box_size, bool periodic, double time) {
  const CollisionlessFields d = fields_of(dm);
  write_ic_file(path, fields_of(gas), &d, box_size, periodic, time);
}

void write_initial_conditions(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                              double box_size, const CosmologicalIcInfo& info) {
  const CollisionlessFields d = fields_of(dm);
  write_ic_file(path, fields_of(gas), &d, {box_size, box_size, box_size}, true, info.a, &info);
}

void write_initial_conditions(const std::string& path, const IcGasParticles& gas, const IcCollisionlessParticles& dm,
                              double box_size, const CosmologicalIcInfo& info) {
  const CollisionlessFields d = fields_of(dm);
  write_ic_file(path, fields_of(gas), &d, {box_size, box_size, box_size}, true, info.a, &info);
}

}  // namespace fountain::io
