#include "io/InitialConditions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numeric>
#include <string>
#include <system_error>
#include <vector>

#include "core/Error.hpp"
#include "io/Hdf5File.hpp"

namespace fountain::io {

namespace {

using hdf5::File;

constexpr const char* kHeader = "/Header";
constexpr const char* kGas = "/PartType0";

std::string gas_dataset(const char* name) { return std::string(kGas) + "/" + name; }

// Checks that `dataset` has n rows (and 3 columns when `vector` is set) before reading it.
void check_shape(const File& file, const std::string& dataset, std::uint64_t n, bool vector) {
  const hdf5::DatasetInfo info = file.dataset_info(dataset);
  const std::size_t want_rank = vector ? 2 : 1;
  if (info.dims.size() != want_rank || (vector && info.dims[1] != 3)) {
    std::string shape;
    for (std::size_t d = 0; d < info.dims.size(); ++d) shape += (d ? " x " : "") + std::to_string(info.dims[d]);
    file.fail(dataset, fmt::format("has shape ({}), expected {}", shape, vector ? "N x 3" : "N"));
  }
  if (info.dims[0] != n)
    file.fail(dataset, fmt::format("has {} entries but /Header/NumPart_ThisFile[0] announces {} gas particles",
                                   info.dims[0], n));
}

std::vector<Vec3> read_vectors(const File& file, const char* name, std::uint64_t n,
                               const std::vector<std::uint64_t>& ids, const char* what) {
  const std::string dataset = gas_dataset(name);
  if (!file.exists(dataset)) file.fail(dataset, "dataset not found");
  check_shape(file, dataset, n, true);
  std::vector<Vec3> values = file.read_vec3(dataset);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const Vec3& v = values[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      file.fail(dataset, fmt::format("particle ID {} has non-finite {} ({}, {}, {})", ids[i], what, v.x, v.y, v.z));
  }
  return values;
}

std::vector<double> read_scalars(const File& file, const char* name, std::uint64_t n) {
  const std::string dataset = gas_dataset(name);
  check_shape(file, dataset, n, false);
  return file.read_doubles(dataset);
}

}  // namespace

InitialConditions read_initial_conditions(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": initial conditions file not found");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, not an HDF5 initial conditions file");
  if (!hdf5::is_hdf5(path)) throw InputError(path + ": not an HDF5 file (expected GADGET-layout HDF5 initial conditions)");

  const File file(path, File::Mode::read);
  if (!file.exists(kHeader)) file.fail(kHeader, "group not found (not a GADGET-layout HDF5 file?)");

  // --- Header ---------------------------------------------------------------------------
  const std::vector<std::uint64_t> this_file = file.read_attribute_uint64(kHeader, "NumPart_ThisFile");
  if (this_file.empty()) file.fail("/Header/NumPart_ThisFile", "is empty");
  const std::uint64_t n = this_file[0];

  if (file.has_attribute(kHeader, "NumFilesPerSnapshot")) {
    const std::vector<std::uint64_t> files = file.read_attribute_uint64(kHeader, "NumFilesPerSnapshot");
    if (!files.empty() && files[0] > 1)
      file.fail("/Header/NumFilesPerSnapshot",
                fmt::format("is {}: initial conditions split over several files are not supported; "
                            "combine them into one file",
                            files[0]));
  }
  if (file.has_attribute(kHeader, "NumPart_Total")) {
    const std::vector<std::uint64_t> total = file.read_attribute_uint64(kHeader, "NumPart_Total");
    std::uint64_t high = 0;
    if (file.has_attribute(kHeader, "NumPart_Total_HighWord")) {
      const std::vector<std::uint64_t> hw = file.read_attribute_uint64(kHeader, "NumPart_Total_HighWord");
      if (!hw.empty()) high = hw[0];
    }
    if (!total.empty()) {
      const std::uint64_t total_gas = total[0] + (high << 32);
      if (total_gas != n)
        file.fail("/Header/NumPart_Total",
                  fmt::format("announces {} gas particles but NumPart_ThisFile[0] is {}", total_gas, n));
    }
  }
  if (n == 0)
    file.fail("/Header/NumPart_ThisFile",
              "has no gas particles (entry 0 is 0); Fountain needs gas particles in /PartType0");

  if (file.has_attribute(kHeader, "Flag_Entropy_ICs")) {
    for (double flag : file.read_attribute_doubles(kHeader, "Flag_Entropy_ICs"))
      if (flag != 0.0)
        file.fail("/Header/Flag_Entropy_ICs",
                  "is set: InternalEnergy holds entropy, which is not supported; write the specific internal "
                  "energy instead");
  }

  InitialConditions ic;

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

  double table_mass = 0.0;
  const bool has_mass_table = file.has_attribute(kHeader, "MassTable");
  if (has_mass_table) {
    const std::vector<double> table = file.read_attribute_doubles(kHeader, "MassTable");
    if (table.empty()) file.fail("/Header/MassTable", "is empty");
    table_mass = table[0];
  }

  // --- Gas particles ------------------------------------------------------------------
  if (!file.exists(kGas))
    file.fail(kGas, fmt::format("group not found, but /Header/NumPart_ThisFile[0] announces {} gas particles", n));

  const std::string ids_name = gas_dataset("ParticleIDs");
  if (!file.exists(ids_name)) file.fail(ids_name, "dataset not found");
  check_shape(file, ids_name, n, false);
  const std::vector<std::uint64_t> ids = file.read_uint64(ids_name);
  {
    std::vector<std::size_t> order(ids.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return ids[a] != ids[b] ? ids[a] < ids[b] : a < b;
    });
    for (std::size_t k = 1; k < order.size(); ++k)
      if (ids[order[k]] == ids[order[k - 1]])
        file.fail(ids_name, fmt::format("particle ID {} appears more than once (entries {} and {}); IDs must be unique",
                                        ids[order[k]], order[k - 1], order[k]));
  }

  const std::vector<Vec3> x = read_vectors(file, "Coordinates", n, ids, "coordinates");
  const std::vector<Vec3> v = read_vectors(file, "Velocities", n, ids, "velocity");

  std::vector<double> mass;
  const std::string mass_name = gas_dataset("Masses");
  if (file.exists(mass_name)) {
    mass = read_scalars(file, "Masses", n);
    for (std::size_t i = 0; i < mass.size(); ++i)
      if (!std::isfinite(mass[i]) || mass[i] <= 0.0)
        file.fail(mass_name, fmt::format("particle ID {} has mass {} (must be positive)", ids[i], mass[i]));
  } else if (!has_mass_table) {
    file.fail(mass_name, "dataset not found and /Header has no MassTable: the gas masses are missing");
  } else if (table_mass == 0.0) {
    file.fail(mass_name, "dataset not found and /Header/MassTable[0] is 0: the gas masses are missing");
  } else if (!std::isfinite(table_mass) || table_mass < 0.0) {
    file.fail("/Header/MassTable", fmt::format("entry 0 (gas) is {} (must be positive)", table_mass));
  } else {
    mass.assign(n, table_mass);
  }

  const std::string u_name = gas_dataset("InternalEnergy");
  if (!file.exists(u_name)) file.fail(u_name, "dataset not found (the gas needs a specific internal energy)");
  const std::vector<double> u = read_scalars(file, "InternalEnergy", n);
  for (std::size_t i = 0; i < u.size(); ++i)
    if (!std::isfinite(u[i]) || u[i] <= 0.0)
      file.fail(u_name,
                fmt::format("particle ID {} has internal energy {} (must be positive and finite)", ids[i], u[i]));

  std::vector<double> h;
  const std::string h_name = gas_dataset("SmoothingLength");
  ic.has_smoothing_length = file.exists(h_name);
  if (ic.has_smoothing_length) {
    h = read_scalars(file, "SmoothingLength", n);
    for (std::size_t i = 0; i < h.size(); ++i)
      if (!std::isfinite(h[i]) || h[i] < 0.0)
        file.fail(h_name, fmt::format("particle ID {} has smoothing length {} (must be finite and non-negative)",
                                      ids[i], h[i]));
  } else {
    h.assign(n, 0.0);
  }

  // --- Fill the particles ---------------------------------------------------------------
  GasParticles& gas = ic.gas;
  gas.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
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
  return ic;
}

namespace {

// Common mass of all entries, or 0 if they differ (for /Header/MassTable).
double common_mass(const std::vector<double>& mass) {
  if (mass.empty()) return 0.0;
  for (double m : mass)
    if (m != mass[0]) return 0.0;
  return mass[0];
}

void write_ic_file(const std::string& path, const GasParticles& gas, const DarkMatterParticles* dm,
                   const Vec3& box_size, bool periodic, double time) {
  const std::size_t n = gas.size();
  const std::string prefix = "cannot create initial conditions " + path + ": ";
  if (n == 0) throw InputError(prefix + "there are no gas particles to write");
  auto check = [&](std::size_t size, const char* field) {
    if (size != n) throw InputError(prefix + fmt::format("gas field {} has {} entries, expected {}", field, size, n));
  };
  check(gas.mass.size(), "mass");
  check(gas.x.size(), "x");
  check(gas.v_full.size(), "v_full");
  check(gas.u_full.size(), "u_full");
  check(gas.h.size(), "h");

  const std::size_t n_dm = dm != nullptr ? dm->size() : 0;
  if (dm != nullptr) {
    auto check_dm = [&](std::size_t size, const char* field) {
      if (size != n_dm)
        throw InputError(prefix + fmt::format("dark matter field {} has {} entries, expected {}", field, size, n_dm));
    };
    check_dm(dm->mass.size(), "mass");
    check_dm(dm->x.size(), "x");
    check_dm(dm->v_full.size(), "v_full");
    for (std::size_t i = 0; i < n_dm; ++i)
      if (!std::isfinite(dm->mass[i]) || dm->mass[i] <= 0.0)
        throw InputError(prefix + fmt::format("dark matter particle ID {} has mass {} (must be positive)", dm->id[i],
                                              dm->mass[i]));
    // IDs must be unique across both types.
    std::vector<std::uint64_t> all(gas.id);
    all.insert(all.end(), dm->id.begin(), dm->id.end());
    std::sort(all.begin(), all.end());
    const auto dup = std::adjacent_find(all.begin(), all.end());
    if (dup != all.end())
      throw InputError(prefix + fmt::format("particle ID {} is used more than once (IDs must be unique across gas "
                                            "and dark matter)",
                                            *dup));
  }

  hdf5::write_file_atomically(path, "initial conditions", [&](File& file) {
    hdf5::write_gadget_header(file, n, {box_size.x, box_size.y, box_size.z}, time);
    // Not a GADGET field; records the boundary conditions the set-up was made for.
    file.write_attribute(kHeader, "Periodic", periodic ? 1 : 0);
    file.create_group(kGas);
    file.write_dataset(gas_dataset("Coordinates"), gas.x);
    file.write_dataset(gas_dataset("Velocities"), gas.v_full);
    file.write_dataset(gas_dataset("ParticleIDs"), gas.id);
    file.write_dataset(gas_dataset("Masses"), gas.mass);
    file.write_dataset(gas_dataset("InternalEnergy"), gas.u_full);
    file.write_dataset(gas_dataset("SmoothingLength"), gas.h);
    if (dm == nullptr) return;

    // The header as written above counts gas only: replace the counts and the mass table.
    constexpr std::uint64_t two32 = std::uint64_t{1} << 32;
    const std::uint64_t counts[2] = {n, n_dm};
    if (n < two32 && n_dm < two32) {
      file.write_attribute(kHeader, "NumPart_ThisFile",
                           std::vector<std::uint32_t>{static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(n_dm),
                                                      0, 0, 0, 0});
    } else {
      file.write_attribute(kHeader, "NumPart_ThisFile", std::vector<std::uint64_t>{n, n_dm, 0, 0, 0, 0});
    }
    std::vector<std::uint32_t> low(6, 0), high(6, 0);
    for (int t = 0; t < 2; ++t) {
      low[t] = static_cast<std::uint32_t>(counts[t] % two32);
      high[t] = static_cast<std::uint32_t>(counts[t] / two32);
    }
    file.write_attribute(kHeader, "NumPart_Total", low);
    file.write_attribute(kHeader, "NumPart_Total_HighWord", high);
    std::vector<double> table(6, 0.0);
    table[0] = common_mass(gas.mass);
    table[1] = common_mass(dm->mass);
    file.write_attribute(kHeader, "MassTable", table);

    const std::string group = "/PartType1";
    file.create_group(group);
    file.write_dataset(group + "/Coordinates", dm->x);
    file.write_dataset(group + "/Velocities", dm->v_full);
    file.write_dataset(group + "/ParticleIDs", dm->id);
    file.write_dataset(group + "/Masses", dm->mass);
  });
}

}  // namespace

void write_initial_conditions(const std::string& path, const GasParticles& gas, const Vec3& box_size,
                              bool periodic, double time) {
  write_ic_file(path, gas, nullptr, box_size, periodic, time);
}

void write_initial_conditions(const std::string& path, const GasParticles& gas, const DarkMatterParticles& dm,
                              const Vec3& box_size, bool periodic, double time) {
  write_ic_file(path, gas, &dm, box_size, periodic, time);
}

}  // namespace fountain::io
