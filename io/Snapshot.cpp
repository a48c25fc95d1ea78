// Snapshot writer.
//
// Which yt frontend reads these files (decided from the yt 4.1 sources):
//  * yt's SWIFT frontend (yt/frontends/swift) accepts a file only if /Header has
//    Code == "SWIFT", and it then also needs the groups /RuntimePars, /Policy, /HydroScheme
//    and /SubgridScheme. Claiming to be SWIFT would be a lie, so we do not.
//  * yt's GadgetHDF5Dataset (yt/frontends/gadget) accepts any HDF5 file with a /Header
//    group, no /FOF, /Group or /Subhalo group, and /Header Code != "SWIFT". Its subclasses
//    (OWLS, EAGLE, Arepo, Gizmo) need groups or datasets we never write (/Constants,
//    /Config, /HashTable, /RuntimePars, GFM_* fields, a 2-D Metallicity), so these files are
//    recognised as plain GADGET HDF5 and nothing else.
//  So the file is a valid GADGET HDF5 snapshot (/Header as GADGET-2 writes it, /PartType0
//  datasets and /PartType1 for dark matter, MassTable zeros with per-particle Masses) with SWIFT's extras on top: /Units
//  (SWIFT attribute names), /Parameters (one "Section:key" string attribute per parameter),
//  /Code, and SWIFT-style unit attributes on every dataset (as swiftsimio reads them:
//  1-element float arrays).
//  Two consequences for yt's GADGET reader:
//  * it needs a scalar /Header/BoxSize (it computes ones(3) * BoxSize), so a cubic box is
//    written as a scalar (GADGET convention) and only a non-cubic box as 3 values (SWIFT
//    convention; yt then needs an explicit bounding_box);
//  * it ignores /Units (it assumes kpc, 1e10 Msun, km/s unless given unit_base), so /Units
//    also carries the GADGET names UnitLength_in_cm, UnitMass_in_g and
//    UnitVelocity_in_cm_per_s, to be passed as yt.load(path, unit_base={...}); see
//    tests/check_snapshot_yt.py.
#include "io/Snapshot.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"
#include "io/FieldDatasets.hpp"
#include "io/Hdf5File.hpp"
#include "particles/ParticleFields.hpp"

namespace fountain::io {

namespace {

using hdf5::File;

// ---- YAML flattening -------------------------------------------------------------------

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// A YAML scalar as text: quotes removed (with their escapes), a trailing comment dropped.
std::string unquote(const std::string& raw) {
  const std::string s = trim(raw);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') {
    std::string out;
    for (std::size_t i = 1; i + 1 < s.size(); ++i) {
      if (s[i] == '\\' && i + 2 < s.size()) {
        const char c = s[++i];
        out += c == 'n' ? '\n' : c == 't' ? '\t' : c;
      } else {
        out += s[i];
      }
    }
    return out;
  }
  if (s.size() >= 2 && s.front() == '\'' && s.back() == '\'') {
    std::string out;
    for (std::size_t i = 1; i + 1 < s.size(); ++i) {
      out += s[i];
      if (s[i] == '\'' && s[i + 1] == '\'') ++i;
    }
    return out;
  }
  const auto hash = s.find(" #");
  return hash == std::string::npos ? s : trim(s.substr(0, hash));
}

// Position of the ':' that ends a mapping key on this (trimmed) line, or npos.
std::size_t key_colon(const std::string& line) {
  std::size_t i = 0;
  if (!line.empty() && (line[0] == '"' || line[0] == '\'')) {
    const auto close = line.find(line[0], 1);
    if (close == std::string::npos) return std::string::npos;
    i = close + 1;
  }
  for (; i < line.size(); ++i)
    if (line[i] == ':' && (i + 1 == line.size() || line[i + 1] == ' ' || line[i + 1] == '\t')) return i;
  return std::string::npos;
}

// Flattens a block-style YAML mapping ("section:" / "  key: value", any depth) into
// ("section:key", "value") pairs, SWIFT's naming of /Parameters attributes. A block
// sequence under a key becomes "[a, b]"; flow values are kept as written.
std::vector<std::pair<std::string, std::string>> flatten_yaml(const std::string& text) {
  struct Frame {
    std::size_t indent;
    std::string name;
    bool has_children = false;
    std::vector<std::string> items;
  };
  std::vector<std::pair<std::string, std::string>> out;
  std::vector<Frame> stack;
  auto pop = [&] {
    Frame f = std::move(stack.back());
    stack.pop_back();
    if (f.has_children) return;
    std::string value;
    if (!f.items.empty()) {
      value = "[";
      for (std::size_t k = 0; k < f.items.size(); ++k) value += (k ? ", " : "") + f.items[k];
      value += "]";
    }
    out.emplace_back(f.name, value);
  };

  std::size_t start = 0;
  while (start <= text.size()) {
    auto end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;

    const std::string content = trim(line);
    if (content.empty() || content[0] == '#' || content == "---" || content == "...") continue;
    const std::size_t indent = line.find_first_not_of(' ');

    if (content[0] == '-' && (content.size() == 1 || content[1] == ' ')) {
      while (!stack.empty() && stack.back().indent > indent) pop();
      if (!stack.empty()) stack.back().items.push_back(unquote(content.substr(1)));
      continue;
    }
    while (!stack.empty() && stack.back().indent >= indent) pop();
    const auto colon = key_colon(content);
    if (colon == std::string::npos) continue;  // not a mapping line; nothing to record
    const std::string key = unquote(content.substr(0, colon));
    const std::string name = stack.empty() ? key : stack.back().name + ":" + key;
    if (!stack.empty()) stack.back().has_children = true;
    const std::string value = trim(content.substr(colon + 1));
    if (value.empty() || value[0] == '#') {
      stack.push_back(Frame{indent, name, false, {}});
    } else {
      out.emplace_back(name, unquote(value));
    }
  }
  while (!stack.empty()) pop();
  return out;
}

// ---- SWIFT-style unit attributes ---------------------------------------------------------

std::string exponent_term(const char* symbol, double e) {
  if (e == 0.0) return "";
  if (e == 1.0) return fmt::format(" {}", symbol);
  return fmt::format(" {}^{}", symbol, e);
}

// How a comoving run's snapshot stores a field held in code variables: stored = held x a^power,
// and the stored values times a^a_exponent are physical. Velocities are stored as GADGET's
// v_pec / sqrt(a) (held: v' = a v_pec), internal energies physical (held: u' = a^2 u, gamma =
// 5/3), accelerations as held (the gravitational g = A'/a^2); other fields as held, with
// SWIFT's exponents.
struct ComovingStorage {
  double power = 0.0;
  double a_exponent = 0.0;
};
ComovingStorage comoving_storage(const std::string& name, const Dimensions& d, double gamma) {
  if (name == "Velocities") return {-1.5, 0.5};
  if (name == "InternalEnergy") return {-3.0 * (gamma - 1.0), 0.0};
  if (name == "GravAcceleration") return {0.0, -2.0};
  return {0.0, a_power(d, gamma)};
}

void write_dataset_units(File& file, const std::string& dataset, const SnapshotInfo& info, const Dimensions& field,
                         const std::string& field_description) {
  const Units& units = info.units;
  // A comoving run's clock is the scale factor: the times it stamps (stars' births,
  // promotions) are values of a, dimensionless.
  const std::string name = dataset.substr(dataset.rfind('/') + 1);
  const bool scale_factors = info.cosmology && (name == "BirthTime" || name == "PromotionTime");
  const Dimensions d = scale_factors ? Dimensions{} : field;
  const std::string description = scale_factors ? field_description + " (scale factors a)" : field_description;
  const double factor = std::pow(units.mass_cgs, d.mass) * std::pow(units.length_cgs, d.length) *
                        std::pow(units.time_cgs(), d.time);
  // h-scaled units (comoving runs): lengths, masses and times are per h.
  const double h_exponent = info.cosmology ? -(d.mass + d.length + d.time) : 0.0;
  const double a_exponent =
      info.cosmology ? comoving_storage(name, d, info.gamma).a_exponent : a_power(d, info.gamma);
  // Non-cosmological runs: a = h = 1, so the physical factor is the same.
  const double physical = info.cosmology ? factor * std::pow(info.time, a_exponent) *
                                               std::pow(info.cosmology->hubble_param, h_exponent)
                                         : factor;
  auto one = [](double v) { return std::vector<double>{v}; };
  file.write_attribute(dataset, "U_M exponent", one(d.mass));
  file.write_attribute(dataset, "U_L exponent", one(d.length));
  file.write_attribute(dataset, "U_t exponent", one(d.time));
  file.write_attribute(dataset, "U_I exponent", one(0.0));
  file.write_attribute(dataset, "U_T exponent", one(0.0));
  file.write_attribute(dataset, "h-scale exponent", one(h_exponent));
  file.write_attribute(dataset, "a-scale exponent", one(a_exponent));
  file.write_attribute(dataset, "Conversion factor to CGS (not including cosmological corrections)", one(factor));
  file.write_attribute(dataset, "Conversion factor to physical CGS (including cosmological corrections)",
                       one(physical));
  file.write_attribute(dataset, "Expression for physical CGS units", unit_expression(d));
  file.write_attribute(dataset, "Description", description);
  // GADGET-4's names for the same: physical cgs = stored a^a_scaling h^h_scaling to_cgs.
  file.write_attribute(dataset, "a_scaling", a_exponent);
  file.write_attribute(dataset, "h_scaling", h_exponent);
  file.write_attribute(dataset, "to_cgs", factor);
}

// Values of a field as a comoving run's snapshot stores them (see ComovingStorage).
template <class Values>
Values stored_values(const Values& held, const std::string& name, const Dimensions& d, const SnapshotInfo& info) {
  if (!info.cosmology) return held;
  const double power = comoving_storage(name, d, info.gamma).power;
  if (power == 0.0) return held;
  const double scale = std::pow(info.time, power);
  Values out(held);
  if constexpr (std::is_same_v<Values, std::vector<Vec3>> || std::is_same_v<Values, std::vector<double>>)
    for (auto& v : out) v = v * scale;
  return out;
}

// Whether a field flagged `when` goes into a snapshot's group (of stars, or not).
bool written(InSnapshots when, const SnapshotInfo& info, bool stars) {
  switch (when) {
    case InSnapshots::never: return false;
    case InSnapshots::always: return true;
    case InSnapshots::with_star_formation: return info.star_formation;
    case InSnapshots::stars_only: return stars;
  }
  return false;
}

// Every field a snapshot's group takes must hold one entry per particle.
template <class Store>
void check_sizes(const Store& p, const SnapshotInfo& info, bool stars, const char* store_name) {
  for_each_field_of(p, [&](const FieldInfo& field, const auto& values) {
    if (written(field.snapshot, info, stars) && values.size() != p.size())
      throw InputError(fmt::format("{} field {} has {} entries, expected {}", store_name, field.key, values.size(),
                                   p.size()));
  });
}

// Positions as a snapshot stores them: in a periodic box, each particle's image in [0, L)
// (a particle drifts out of the box between the recuts that fold it back).
std::vector<Vec3> positions_in_box(std::span<const Vec3> held, const SnapshotInfo& info) {
  std::vector<Vec3> x(held.begin(), held.end());
  if (info.periodic)
    for (Vec3& p : x) p = wrap_into_box(p, info.box_size);
  return x;
}

// The header groups every snapshot has: /Header (and a comoving run's /Cosmology), /Units,
// /Parameters, /Code.
void write_header_groups(File& file, const SnapshotInfo& info, const SnapshotCounts& counts) {
  const Units& units = info.units;
  const Vec3& b = info.box_size;
  const bool cubic = b.x == b.y && b.y == b.z;

  hdf5::write_gadget_header(file, {counts.gas, counts.dark_matter, counts.low_res, 0, counts.stars, 0},
                            cubic ? std::vector<double>{b.x} : std::vector<double>{b.x, b.y, b.z}, info.time,
                            info.cosmology ? &*info.cosmology : nullptr);
  if (info.cosmology) {
    // SWIFT's /Cosmology group.
    const cosmology::CosmologyParams& c = *info.cosmology;
    file.create_group("/Cosmology");
    file.write_attribute("/Cosmology", "Cosmological run", 1);
    file.write_attribute("/Cosmology", "Scale-factor", info.time);
    file.write_attribute("/Cosmology", "Redshift", 1.0 / info.time - 1.0);
    file.write_attribute("/Cosmology", "Omega_m", c.omega_m);
    file.write_attribute("/Cosmology", "Omega_lambda", c.omega_lambda);
    file.write_attribute("/Cosmology", "Omega_b", c.omega_b);
    file.write_attribute("/Cosmology", "Omega_k", c.omega_k());
    file.write_attribute("/Cosmology", "h", c.hubble_param);
  }
  file.write_attribute("/Header", "Code", "Fountain");
  file.write_attribute("/Header", "Periodic", info.periodic ? 1 : 0);
  file.write_attribute("/Header", "Step", static_cast<std::int64_t>(info.step));

  // /Units (SWIFT names, 1-element arrays as SWIFT writes them; plus the GADGET names)
  file.create_group("/Units");
  file.write_attribute("/Units", "Unit length in cgs (U_L)", std::vector<double>{units.length_cgs});
  file.write_attribute("/Units", "Unit mass in cgs (U_M)", std::vector<double>{units.mass_cgs});
  file.write_attribute("/Units", "Unit time in cgs (U_t)", std::vector<double>{units.time_cgs()});
  file.write_attribute("/Units", "Unit current in cgs (U_I)", std::vector<double>{1.0});
  file.write_attribute("/Units", "Unit temperature in cgs (U_T)", std::vector<double>{1.0});
  file.write_attribute("/Units", "UnitLength_in_cm", units.length_cgs);
  file.write_attribute("/Units", "UnitMass_in_g", units.mass_cgs);
  file.write_attribute("/Units", "UnitVelocity_in_cm_per_s", units.velocity_cgs);

  // /Parameters: one string attribute per key, and the whole YAML text as a dataset
  file.create_group("/Parameters");
  for (const auto& [key, value] : flatten_yaml(info.parameters_yaml)) file.write_attribute("/Parameters", key, value);
  file.write_string_dataset("/Parameters/YAML", info.parameters_yaml);

  // /Code
  file.create_group("/Code");
  file.write_attribute("/Code", "Code", "Fountain");
  file.write_attribute("/Code", "Git Revision", info.git_revision);
  file.write_attribute("/Code", "Build options", info.build_options);
  unsigned major = 0, minor = 0, release = 0;
  H5get_libversion(&major, &minor, &release);
  file.write_attribute("/Code", "HDF5 library version", fmt::format("{}.{}.{}", major, minor, release));
}

// The datasets of a group of `rows` particles of `Store`'s kind, with their unit attributes
// (the values come later, in runs of rows).
template <class Store>
void create_group_datasets(File& file, const std::string& group, std::size_t rows, const SnapshotInfo& info,
                           bool stars) {
  const Store like;
  file.create_group(group);
  for_each_field_of(like, [&](const FieldInfo& field, const auto& values) {
    if (!written(field.snapshot, info, stars)) return;
    const std::string dataset = group + "/" + field.name;
    create_field(file, dataset, rows, values);
    write_dataset_units(file, dataset, info, field.units, field.description);
  });
}

// The table's snapshot fields of the particles `pick` (indices into `p`) as rows `row` on of
// `group`'s datasets.
template <class Store>
void write_group_rows(File& file, const std::string& group, const Store& p, std::span<const std::size_t> pick,
                      std::size_t row, const SnapshotInfo& info, bool stars) {
  for_each_field_of(p, [&](const FieldInfo& field, const auto& values) {
    if (!written(field.snapshot, info, stars)) return;
    using Value = typename std::decay_t<decltype(values)>::value_type;
    std::vector<Value> picked;
    picked.reserve(pick.size());
    for (std::size_t i : pick) picked.push_back(values[i]);
    const std::string dataset = group + "/" + field.name;
    // Positions are folded into the box; a comoving run's velocities and energies converted.
    if constexpr (std::is_same_v<Value, Vec3>) {
      if (&values == &p.x) {
        write_field_rows(file, dataset, row, std::span<const Vec3>(positions_in_box(picked, info)));
      } else {
        write_field_rows(file, dataset, row, std::span<const Vec3>(stored_values(picked, field.name, field.units, info)));
      }
    } else if constexpr (std::is_same_v<Value, double>) {
      write_field_rows(file, dataset, row, std::span<const double>(stored_values(picked, field.name, field.units, info)));
    } else {
      write_field_rows(file, dataset, row, std::span<const Value>(picked));
    }
  });
}

void check_stores(const std::string& path, const GasParticles& gas, const CollisionlessParticles* dm,
                  const SnapshotInfo& info) {
  try {
    check_sizes(gas, info, false, "gas");
    if (dm != nullptr) {
      if (dm->species.size() != dm->size())
        throw InputError(fmt::format("collisionless field species has {} entries, expected {}", dm->species.size(),
                                     dm->size()));
      check_sizes(*dm, info, true, "collisionless");
    }
  } catch (const InputError& e) {
    throw InputError("cannot create snapshot " + path + ": " + e.what());
  }
}

// The collisionless species in a snapshot, with their groups.
struct CollisionlessGroup {
  Species species;
  const char* group;
};
constexpr CollisionlessGroup kCollisionlessGroups[] = {
    {Species::DarkMatter, "/PartType1"}, {Species::LowResDarkMatter, "/PartType2"}, {Species::Star, "/PartType4"}};

std::size_t count_of(const SnapshotCounts& counts, Species s) {
  return s == Species::DarkMatter ? counts.dark_matter : s == Species::LowResDarkMatter ? counts.low_res : counts.stars;
}

}  // namespace

struct SnapshotWriter::Impl {
  std::string path;
  SnapshotInfo info;
  SnapshotCounts counts;
  hdf5::AtomicFile file;
  std::size_t gas_rows = 0;
  std::array<std::size_t, 3> collisionless_rows{};  // per kCollisionlessGroups entry
  std::vector<std::size_t> pick;
  Impl(const std::string& p, const SnapshotInfo& i, const SnapshotCounts& c)
      : path(p), info(i), counts(c), file(p, "snapshot") {}
};

SnapshotWriter::SnapshotWriter(const std::string& path, const SnapshotInfo& info, const SnapshotCounts& counts)
    : impl_(std::make_unique<Impl>(path, info, counts)) {
  impl_->file.write([&](File& file) {
    write_header_groups(file, info, counts);
    // /PartType0: the table's fields, then those worked out from them.
    create_group_datasets<GasParticles>(file, "/PartType0", counts.gas, info, false);
    file.create_rows_dataset("/PartType0/" + std::string(kPressureDataset.name), hdf5::File::RowType::float64,
                             counts.gas);
    write_dataset_units(file, "/PartType0/" + std::string(kPressureDataset.name), info, kPressureDataset.units,
                        fmt::format("{} with gamma = {}", kPressureDataset.description, info.gamma));
    if (info.temperature) {
      const std::string ds = "/PartType0/" + std::string(kTemperatureDataset.name);
      file.create_rows_dataset(ds, hdf5::File::RowType::float64, counts.gas);
      write_dataset_units(file, ds, info, kTemperatureDataset.units, kTemperatureDataset.description);
    }
    // /PartType1 (dark matter), /PartType2 (lower-resolution dark matter) and /PartType4
    // (stars): MassTable stays 0, masses per particle.
    for (const CollisionlessGroup& g : kCollisionlessGroups)
      if (count_of(counts, g.species) > 0)
        create_group_datasets<CollisionlessParticles>(file, g.group, count_of(counts, g.species), info,
                                                      g.species == Species::Star);
  });
}

SnapshotWriter::~SnapshotWriter() = default;

void SnapshotWriter::add_gas(const GasParticles& gas, std::size_t first, std::size_t count) {
  Impl& w = *impl_;
  if (first + count > gas.size() || w.gas_rows + count > w.counts.gas)
    throw std::logic_error(fmt::format("snapshot {}: {} more gas particles after {} of {}", w.path, count, w.gas_rows,
                                       w.counts.gas));
  w.pick.resize(count);
  for (std::size_t k = 0; k < count; ++k) w.pick[k] = first + k;
  w.file.write([&](File& file) {
    write_group_rows(file, "/PartType0", gas, w.pick, w.gas_rows, w.info, false);
    const double gm1 = w.info.gamma - 1.0;
    std::vector<double> values(count);
    for (std::size_t k = 0; k < count; ++k) values[k] = gm1 * gas.rho[first + k] * gas.u[first + k];
    file.write_rows("/PartType0/" + std::string(kPressureDataset.name), w.gas_rows, std::span<const double>(values));
    if (w.info.temperature) {
      // Of the physical u (a comoving run holds u' = a^(3 (gamma - 1)) u).
      const double to_physical = w.info.cosmology ? std::pow(w.info.time, -3.0 * gm1) : 1.0;
      for (std::size_t k = 0; k < count; ++k) values[k] = w.info.temperature(gas.u[first + k] * to_physical);
      file.write_rows("/PartType0/" + std::string(kTemperatureDataset.name), w.gas_rows,
                      std::span<const double>(values));
    }
  });
  w.gas_rows += count;
}

void SnapshotWriter::add_collisionless(const CollisionlessParticles& p, std::size_t first, std::size_t count) {
  Impl& w = *impl_;
  if (first + count > p.size()) throw std::logic_error(fmt::format("snapshot {}: collisionless particles {} to {} of {}",
                                                                   w.path, first, first + count, p.size()));
  for (std::size_t g = 0; g < std::size(kCollisionlessGroups); ++g) {
    const CollisionlessGroup& group = kCollisionlessGroups[g];
    w.pick.clear();
    for (std::size_t i = first; i < first + count; ++i)
      if (p.species[i] == group.species) w.pick.push_back(i);
    if (w.pick.empty()) continue;
    std::size_t& rows = w.collisionless_rows[g];
    if (rows + w.pick.size() > count_of(w.counts, group.species))
      throw std::logic_error(fmt::format("snapshot {}: {} more {} particles after {} of {}", w.path, w.pick.size(),
                                         group.group, rows, count_of(w.counts, group.species)));
    w.file.write([&](File& file) {
      write_group_rows(file, group.group, p, w.pick, rows, w.info, group.species == Species::Star);
    });
    rows += w.pick.size();
  }
}

void SnapshotWriter::close() {
  Impl& w = *impl_;
  bool complete = w.gas_rows == w.counts.gas;
  for (std::size_t g = 0; g < std::size(kCollisionlessGroups); ++g)
    complete = complete && w.collisionless_rows[g] == count_of(w.counts, kCollisionlessGroups[g].species);
  if (!complete) throw std::logic_error(fmt::format("snapshot {} closed with {} of {} gas particles written", w.path,
                                                    w.gas_rows, w.counts.gas));
  w.file.commit();
}

namespace {

void write_snapshot_file(const std::string& path, const GasParticles& gas, const CollisionlessParticles* dm,
                         const SnapshotInfo& info) {
  check_stores(path, gas, dm, info);
  SnapshotCounts counts{gas.size(), 0, 0, 0};
  if (dm != nullptr)
    counts = {gas.size(), dm->count(Species::DarkMatter), dm->count(Species::LowResDarkMatter), dm->count(Species::Star)};
  SnapshotWriter writer(path, info, counts);
  writer.add_gas(gas, 0, gas.size());
  if (dm != nullptr) writer.add_collisionless(*dm, 0, dm->size());
  writer.close();
}

}  // namespace

std::string unit_expression(const Dimensions& d) {
  const std::string expression = exponent_term("U_M", d.mass) + exponent_term("U_L", d.length) +
                                 exponent_term("U_t", d.time);
  return expression.empty() ? "[ - ]" : trim(expression);
}

void write_snapshot(const std::string& path, const GasParticles& gas, const SnapshotInfo& info) {
  write_snapshot_file(path, gas, nullptr, info);
}

void write_snapshot(const std::string& path, const GasParticles& gas, const CollisionlessParticles& dm,
                    const SnapshotInfo& info) {
  write_snapshot_file(path, gas, &dm, info);
}

}  // namespace fountain::io
