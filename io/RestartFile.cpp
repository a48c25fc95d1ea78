#include "io/RestartFile.hpp"

#include <fmt/format.h>

#include <concepts>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "core/Error.hpp"
#include "io/Hdf5File.hpp"

namespace fountain::io {

namespace {

// FNV-1a over the bytes of everything stored, in a fixed order.
class Checksum {
 public:
  void add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) {
      hash_ ^= p[k];
      hash_ *= 1099511628211ULL;
    }
  }
  template <class T>
  void add(const std::vector<T>& v) {
    add(v.data(), v.size() * sizeof(T));
  }
  std::string hex() const { return fmt::format("{:016x}", hash_); }

 private:
  std::uint64_t hash_ = 1469598103934665603ULL;
};

// Every field of each particle type, by name, in the order it is stored and checksummed:
// `fn(name, field)` is called once per field. A field added to a particle type must be
// added here, or a restarted run would not continue bit for bit.
template <class Gas, class Fn>
  requires std::same_as<std::remove_const_t<Gas>, GasParticles>
void for_each_field(Gas& g, Fn&& fn) {
  fn("id", g.id);
  fn("ti_begin", g.ti_begin);
  fn("mass", g.mass);
  fn("mass_initial", g.mass_initial);
  fn("mass_stars_hidden", g.mass_stars_hidden);
  fn("reservoir", g.reservoir);
  fn("promoted", g.promoted);
  fn("promotion_time", g.promotion_time);
  fn("feedback_hot_energy", g.feedback_hot_energy);
  fn("u_full", g.u_full);
  fn("u", g.u);
  fn("h", g.h);
  fn("rho", g.rho);
  fn("rho_msph", g.rho_msph);
  fn("h_msph", g.h_msph);
  fn("wcount", g.wcount);
  fn("wcount_dh", g.wcount_dh);
  fn("div_v", g.div_v);
  fn("soundspeed", g.soundspeed);
  fn("p_over_rho_a", g.p_over_rho_a);
  fn("inv_rho_2ma", g.inv_rho_2ma);
  fn("balsara", g.balsara);
  fn("du_dt", g.du_dt);
  fn("du_dt_cool", g.du_dt_cool);
  fn("potential", g.potential);
  fn("x", g.x);
  fn("v_full", g.v_full);
  fn("v", g.v);
  fn("curl_v", g.curl_v);
  fn("a_hydro", g.a_hydro);
  fn("a_grav", g.a_grav);
  fn("time_bin", g.time_bin);
  fn("courant_bin", g.courant_bin);
  fn("limit_bin", g.limit_bin);
  fn("wake_bin", g.wake_bin);
}

template <class Dm, class Fn>
  requires std::same_as<std::remove_const_t<Dm>, CollisionlessParticles>
void for_each_field(Dm& d, Fn&& fn) {
  fn("id", d.id);
  fn("species", d.species);
  fn("birth_time", d.birth_time);
  fn("parent_id", d.parent_id);
  fn("ti_begin", d.ti_begin);
  fn("mass", d.mass);
  fn("potential", d.potential);
  fn("x", d.x);
  fn("v_full", d.v_full);
  fn("v", d.v);
  fn("a_grav", d.a_grav);
  fn("time_bin", d.time_bin);
}

constexpr const char* kGasGroup = "/Gas";
constexpr const char* kDarkMatterGroup = "/DarkMatter";

// ---- One field in the file (integer times as uint64, time bins as int32) -------------------

void write_field(hdf5::File& f, const std::string& name, const std::vector<double>& v) { f.write_dataset(name, v); }
void write_field(hdf5::File& f, const std::string& name, const std::vector<Vec3>& v) { f.write_dataset(name, v); }
void write_field(hdf5::File& f, const std::string& name, const std::vector<std::uint64_t>& v) {
  f.write_dataset(name, v);
}
void write_field(hdf5::File& f, const std::string& name, const std::vector<std::int64_t>& v) {
  f.write_dataset(name, std::vector<std::uint64_t>(v.begin(), v.end()));
}
void write_field(hdf5::File& f, const std::string& name, const std::vector<TimeBin>& v) {
  f.write_dataset(name, std::vector<std::int32_t>(v.begin(), v.end()));
}
void write_field(hdf5::File& f, const std::string& name, const std::vector<std::uint8_t>& v) {
  f.write_dataset(name, std::vector<std::int32_t>(v.begin(), v.end()));
}
void write_field(hdf5::File& f, const std::string& name, const std::vector<Species>& v) {
  std::vector<std::int32_t> raw(v.size());
  for (std::size_t k = 0; k < v.size(); ++k) raw[k] = static_cast<std::int32_t>(v[k]);
  f.write_dataset(name, raw);
}

void read_field(const hdf5::File& f, const std::string& name, std::vector<double>& v) { v = f.read_doubles(name); }
void read_field(const hdf5::File& f, const std::string& name, std::vector<Vec3>& v) { v = f.read_vec3(name); }
void read_field(const hdf5::File& f, const std::string& name, std::vector<std::uint64_t>& v) {
  v = f.read_uint64(name);
}
void read_field(const hdf5::File& f, const std::string& name, std::vector<std::int64_t>& v) {
  const std::vector<std::uint64_t> raw = f.read_uint64(name);
  v.assign(raw.size(), 0);
  for (std::size_t k = 0; k < raw.size(); ++k) v[k] = static_cast<std::int64_t>(raw[k]);
}
void read_field(const hdf5::File& f, const std::string& name, std::vector<TimeBin>& v) {
  const std::vector<double> raw = f.read_doubles(name);
  v.assign(raw.size(), 0);
  for (std::size_t k = 0; k < raw.size(); ++k) v[k] = static_cast<TimeBin>(raw[k]);
}
void read_field(const hdf5::File& f, const std::string& name, std::vector<std::uint8_t>& v) {
  const std::vector<double> raw = f.read_doubles(name);
  v.assign(raw.size(), 0);
  for (std::size_t k = 0; k < raw.size(); ++k) v[k] = static_cast<std::uint8_t>(raw[k]);
}
void read_field(const hdf5::File& f, const std::string& name, std::vector<Species>& v) {
  const std::vector<double> raw = f.read_doubles(name);
  v.assign(raw.size(), Species::DarkMatter);
  for (std::size_t k = 0; k < raw.size(); ++k) v[k] = static_cast<Species>(static_cast<int>(raw[k]));
}

// The star formation tally as numbers, in a fixed order (stored as one attribute).
std::vector<double> tally_values(const starformation::StarFormationTally& t) {
  return {t.mass_formed, t.thermal_locked, t.energy_own, t.energy_reservoir, t.energy_hot, t.energy_released,
          t.kinetic_to_heat, static_cast<double>(t.promotions), static_cast<double>(t.stars_spawned),
          static_cast<double>(t.gas_dissolved), static_cast<double>(t.hot_without_neighbours)};
}
starformation::StarFormationTally tally_from(const std::vector<double>& v) {
  starformation::StarFormationTally t;
  if (v.size() != 11) return t;
  t.mass_formed = v[0]; t.thermal_locked = v[1]; t.energy_own = v[2]; t.energy_reservoir = v[3];
  t.energy_hot = v[4]; t.energy_released = v[5]; t.kinetic_to_heat = v[6];
  t.promotions = static_cast<long long>(v[7]); t.stars_spawned = static_cast<long long>(v[8]);
  t.gas_dissolved = static_cast<long long>(v[9]); t.hot_without_neighbours = static_cast<long long>(v[10]);
  return t;
}

// ---- A whole particle type ---------------------------------------------------------------

template <class Particles>
void add_to_checksum(Checksum& c, const Particles& p) {
  for_each_field(p, [&](const char*, const auto& field) { c.add(field); });
}

template <class Particles>
void write_particles(hdf5::File& f, const std::string& group, const Particles& p) {
  f.create_group(group);
  for_each_field(p, [&](const char* name, const auto& field) { write_field(f, group + "/" + name, field); });
}

// Reads every field of `group`; each must hold `count` entries (the count in /Restart).
template <class Particles>
Particles read_particles(const hdf5::File& f, const std::string& path, const std::string& group,
                         std::uint64_t count, const char* noun) {
  Particles p;
  for_each_field(p, [&](const char* name, auto& field) {
    const std::string dataset = group + "/" + name;
    if (!f.exists(dataset)) throw InputError(fmt::format("{}: {} not found (restart file incomplete)", path, dataset));
    read_field(f, dataset, field);
    if (field.size() != count)
      throw InputError(fmt::format("{}: {} has {} entries, but the file holds {} {} particles", path, dataset,
                                   field.size(), count, noun));
  });
  return p;
}

std::string scalars_checksum_text(const RestartState& s) {
  std::string text = fmt::format("{} {} {} {} {} {} {:a} {}", s.ti_current, s.steps, s.snapshots_written,
                                 s.next_output, s.gas.size(), s.dm.size(), s.radiated_energy, s.next_particle_id);
  for (double v : tally_values(s.star_formation)) text += fmt::format(" {:a}", v);
  return text;
}

std::string checksum(const RestartState& s) {
  Checksum c;
  const std::string scalars = scalars_checksum_text(s);
  c.add(scalars.data(), scalars.size());
  c.add(s.parameters_yaml.data(), s.parameters_yaml.size());
  add_to_checksum(c, s.gas);
  add_to_checksum(c, s.dm);
  return c.hex();
}

}  // namespace

void write_restart(const std::string& path, const RestartState& s) {
  hdf5::write_file_atomically(path, "restart file", [&](hdf5::File& f) {
    f.create_group("/Restart");
    f.write_attribute("/Restart", "FormatVersion", kRestartFormatVersion);
    f.write_attribute("/Restart", "TiCurrent", static_cast<std::int64_t>(s.ti_current));
    f.write_attribute("/Restart", "Steps", static_cast<std::int64_t>(s.steps));
    f.write_attribute("/Restart", "SnapshotsWritten", s.snapshots_written);
    f.write_attribute("/Restart", "NextOutput", s.next_output);
    f.write_attribute("/Restart", "RadiatedEnergy", s.radiated_energy);
    f.write_attribute("/Restart", "NextParticleId", std::vector<std::uint64_t>{s.next_particle_id});
    f.write_attribute("/Restart", "StarFormationTally", tally_values(s.star_formation));
    f.write_attribute("/Restart", "GasParticles", static_cast<std::int64_t>(s.gas.size()));
    f.write_attribute("/Restart", "CollisionlessParticles", static_cast<std::int64_t>(s.dm.size()));
    f.write_string_dataset("/Restart/Parameters", s.parameters_yaml.empty() ? std::string("{}") : s.parameters_yaml);
    f.write_attribute("/Restart", "Checksum", checksum(s));
    write_particles(f, kGasGroup, s.gas);
    write_particles(f, kDarkMatterGroup, s.dm);
  });
}

RestartState read_restart(const std::string& path) {
  if (!std::filesystem::exists(path)) throw InputError(fmt::format("{}: no such restart file", path));
  if (!hdf5::is_hdf5(path)) throw InputError(fmt::format("{}: not a restart file (not HDF5, or truncated)", path));
  hdf5::File f(path, hdf5::File::Mode::read);
  if (!f.exists("/Restart") || !f.has_attribute("/Restart", "FormatVersion"))
    throw InputError(fmt::format("{}: not a Fountain restart file", path));
  const auto version = static_cast<int>(f.read_attribute_double("/Restart", "FormatVersion"));
  if (version != kRestartFormatVersion)
    throw InputError(fmt::format("{}: restart format version {} cannot be read by this build (it reads version {})",
                                 path, version, kRestartFormatVersion));
  for (const char* name : {"TiCurrent", "Steps", "SnapshotsWritten", "NextOutput", "RadiatedEnergy", "NextParticleId",
                           "StarFormationTally", "GasParticles", "CollisionlessParticles", "Checksum"})
    if (!f.has_attribute("/Restart", name))
      throw InputError(fmt::format("{}: /Restart has no attribute {} (restart file incomplete)", path, name));
  RestartState s;
  s.ti_current = f.read_attribute_int64("/Restart", "TiCurrent").at(0);
  s.steps = f.read_attribute_int64("/Restart", "Steps").at(0);
  s.snapshots_written = static_cast<int>(f.read_attribute_double("/Restart", "SnapshotsWritten"));
  s.next_output = static_cast<int>(f.read_attribute_double("/Restart", "NextOutput"));
  s.radiated_energy = f.read_attribute_double("/Restart", "RadiatedEnergy");
  s.next_particle_id = f.read_attribute_uint64("/Restart", "NextParticleId").at(0);
  s.star_formation = tally_from(f.read_attribute_doubles("/Restart", "StarFormationTally"));
  s.parameters_yaml = f.read_string("/Restart/Parameters");
  if (s.parameters_yaml == "{}") s.parameters_yaml.clear();
  const std::uint64_t n_gas = f.read_attribute_uint64("/Restart", "GasParticles").at(0);
  const std::uint64_t n_dm = f.read_attribute_uint64("/Restart", "CollisionlessParticles").at(0);
  s.gas = read_particles<GasParticles>(f, path, kGasGroup, n_gas, "gas");
  s.dm = read_particles<CollisionlessParticles>(f, path, kDarkMatterGroup, n_dm, "collisionless");
  const std::string stored = f.read_attribute_string("/Restart", "Checksum");
  if (stored != checksum(s))
    throw InputError(fmt::format("{}: restart file is corrupted (checksum {} does not match its contents)", path, stored));
  return s;
}

}  // namespace fountain::io
