#include "io/RestartFile.hpp"

#include <fmt/format.h>

#include <cstring>
#include <filesystem>

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

// The double fields of the gas, by name, in the order they are checksummed.
template <class Gas>
auto double_fields(Gas& g) {
  return std::vector<std::pair<const char*, decltype(&g.mass)>>{
      {"mass", &g.mass},         {"u_full", &g.u_full},   {"u", &g.u},           {"h", &g.h},
      {"rho", &g.rho},           {"rho_msph", &g.rho_msph}, {"h_msph", &g.h_msph}, {"wcount", &g.wcount},
      {"wcount_dh", &g.wcount_dh}, {"div_v", &g.div_v},
      {"soundspeed", &g.soundspeed}, {"p_over_rho_a", &g.p_over_rho_a}, {"inv_rho_2ma", &g.inv_rho_2ma}, {"balsara", &g.balsara},
      {"du_dt", &g.du_dt}};
}
template <class Gas>
auto vector_fields(Gas& g) {
  return std::vector<std::pair<const char*, decltype(&g.x)>>{
      {"x", &g.x}, {"v_full", &g.v_full}, {"v", &g.v}, {"curl_v", &g.curl_v}, {"a_hydro", &g.a_hydro}};
}
template <class Gas>
auto bin_fields(Gas& g) {
  return std::vector<std::pair<const char*, decltype(&g.time_bin)>>{
      {"time_bin", &g.time_bin}, {"courant_bin", &g.courant_bin}, {"limit_bin", &g.limit_bin}, {"wake_bin", &g.wake_bin}};
}

std::string scalars_checksum_text(const RestartState& s) {
  return fmt::format("{} {} {} {} {}", s.ti_current, s.steps, s.snapshots_written, s.next_output, s.gas.size());
}

std::string checksum(const RestartState& s) {
  Checksum c;
  const std::string scalars = scalars_checksum_text(s);
  c.add(scalars.data(), scalars.size());
  c.add(s.parameters_yaml.data(), s.parameters_yaml.size());
  c.add(s.gas.id);
  c.add(s.gas.ti_begin);
  for (auto& [name, f] : double_fields(s.gas)) c.add(*f);
  for (auto& [name, f] : vector_fields(s.gas)) c.add(*f);
  for (auto& [name, f] : bin_fields(s.gas)) c.add(*f);
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
    f.write_string_dataset("/Restart/Parameters", s.parameters_yaml.empty() ? std::string("{}") : s.parameters_yaml);
    f.write_attribute("/Restart", "Checksum", checksum(s));
    f.create_group("/Gas");
    f.write_dataset("/Gas/id", s.gas.id);
    std::vector<std::uint64_t> ti(s.gas.ti_begin.begin(), s.gas.ti_begin.end());
    f.write_dataset("/Gas/ti_begin", ti);
    for (auto& [name, field] : double_fields(s.gas)) f.write_dataset(std::string("/Gas/") + name, *field);
    for (auto& [name, field] : vector_fields(s.gas)) f.write_dataset(std::string("/Gas/") + name, *field);
    for (auto& [name, field] : bin_fields(s.gas)) {
      std::vector<std::int32_t> b(field->begin(), field->end());
      f.write_dataset(std::string("/Gas/") + name, b);
    }
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
  RestartState s;
  s.ti_current = f.read_attribute_int64("/Restart", "TiCurrent").at(0);
  s.steps = f.read_attribute_int64("/Restart", "Steps").at(0);
  s.snapshots_written = static_cast<int>(f.read_attribute_double("/Restart", "SnapshotsWritten"));
  s.next_output = static_cast<int>(f.read_attribute_double("/Restart", "NextOutput"));
  s.parameters_yaml = f.read_string("/Restart/Parameters");
  if (s.parameters_yaml == "{}") s.parameters_yaml.clear();
  const auto ids = f.read_uint64("/Gas/id");
  s.gas.resize(ids.size());
  s.gas.id = ids;
  const auto ti = f.read_uint64("/Gas/ti_begin");
  for (std::size_t k = 0; k < ti.size() && k < s.gas.size(); ++k) s.gas.ti_begin[k] = static_cast<std::int64_t>(ti[k]);
  auto check_size = [&](const std::string& name, std::size_t n) {
    if (n != s.gas.size())
      throw InputError(fmt::format("{}: /Gas/{} has {} entries, expected {}", path, name, n, s.gas.size()));
  };
  check_size("ti_begin", ti.size());
  for (auto& [name, field] : double_fields(s.gas)) {
    *field = f.read_doubles(std::string("/Gas/") + name);
    check_size(name, field->size());
  }
  for (auto& [name, field] : vector_fields(s.gas)) {
    *field = f.read_vec3(std::string("/Gas/") + name);
    check_size(name, field->size());
  }
  for (auto& [name, field] : bin_fields(s.gas)) {
    const auto b = f.read_doubles(std::string("/Gas/") + name);
    check_size(name, b.size());
    for (std::size_t k = 0; k < b.size(); ++k) (*field)[k] = static_cast<TimeBin>(b[k]);
  }
  const std::string stored = f.read_attribute_string("/Restart", "Checksum");
  if (stored != checksum(s))
    throw InputError(fmt::format("{}: restart file is corrupted (checksum {} does not match its contents)", path, stored));
  return s;
}

}  // namespace fountain::io
