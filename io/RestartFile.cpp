#include "io/RestartFile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "core/Error.hpp"
#include "io/FieldDatasets.hpp"
#include "io/Hdf5File.hpp"
#include "particles/ParticleFields.hpp"

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

// The fields of a store that restart files hold, in table order (the order they are stored
// and checksummed in): `fn(name, field)` once per field. Every other field is a new particle's
// value after a read.
template <class Particles, class Fn>
void for_each_restart_field(Particles& p, Fn&& fn) {
  for_each_field_of(p, [&](const FieldInfo& field, auto& values) {
    if (field.restart) fn(field.key, values);
  });
}

constexpr const char* kGasGroup = "/Gas";
constexpr const char* kDarkMatterGroup = "/DarkMatter";

// The star formation tally as numbers, in a fixed order (stored as one attribute).
std::vector<double> tally_values(const star_formation::StarFormationTally& t) {
  return {t.mass_formed, t.thermal_locked, t.energy_own, t.energy_reservoir, t.energy_hot, t.energy_released,
          t.kinetic_to_heat, static_cast<double>(t.promotions), static_cast<double>(t.stars_spawned),
          static_cast<double>(t.gas_dissolved), static_cast<double>(t.hot_without_neighbours), t.energy_promoted};
}
star_formation::StarFormationTally tally_from(const std::vector<double>& v) {
  star_formation::StarFormationTally t;
  // Files written before energy_promoted was kept have 11 values (it is then 0).
  if (v.size() != 11 && v.size() != 12) return t;
  t.mass_formed = v[0]; t.thermal_locked = v[1]; t.energy_own = v[2]; t.energy_reservoir = v[3];
  t.energy_hot = v[4]; t.energy_released = v[5]; t.kinetic_to_heat = v[6];
  t.promotions = static_cast<long long>(v[7]); t.stars_spawned = static_cast<long long>(v[8]);
  t.gas_dissolved = static_cast<long long>(v[9]); t.hot_without_neighbours = static_cast<long long>(v[10]);
  if (v.size() == 12) t.energy_promoted = v[11];
  return t;
}

// ---- A whole particle type ---------------------------------------------------------------

// Writes the restart fields of `p` (its rows `rows`, in that order, or all of them) and adds
// each to the checksum as read_particle_rows does: a field of the rows is gathered alone, so
// the store is never copied whole.
template <class Particles>
void write_particles(hdf5::File& f, const std::string& group, const Particles& p, Checksum& c,
                     const std::vector<std::size_t>* rows = nullptr) {
  f.create_group(group);
  for_each_restart_field(p, [&](const char* name, const auto& field) {
    if (rows == nullptr) {
      write_field(f, group + "/" + name, field);
      c.add(field);
      return;
    }
    std::decay_t<decltype(field)> picked(rows->size());
    for (std::size_t k = 0; k < rows->size(); ++k) picked[k] = field[(*rows)[k]];
    write_field(f, group + "/" + name, picked);
    c.add(picked);
  });
}

// n_gas and n_dm: the whole run's particle counts.
std::string scalars_checksum_text(const RestartState& s, std::uint64_t n_gas, std::uint64_t n_dm) {
  std::string text = fmt::format("{} {} {} {} {} {} {} {:a} {} {} {}", s.ti_current, s.ti_step_begin, s.steps,
                                 s.snapshots_written, s.next_output, n_gas, n_dm, s.radiated_energy,
                                 s.next_particle_id, s.mesh_step_bin, s.mesh_step_begin);
  for (double v : tally_values(s.star_formation)) text += fmt::format(" {:a}", v);
  return text;
}

void add_scalars_to_checksum(Checksum& c, const RestartState& s, std::uint64_t n_gas, std::uint64_t n_dm) {
  const std::string scalars = scalars_checksum_text(s, n_gas, n_dm);
  c.add(scalars.data(), scalars.size());
  c.add(s.parameters_yaml.data(), s.parameters_yaml.size());
}

// Reads every field of `group` (each must hold `count` rows, the count the file states) a run
// of `rows_per_read` rows at a time (0: all at once), adds each field's rows to the checksum in
// the order write_particles adds them, and keeps the rows of `keep`: the memory this takes is
// what it keeps plus one run of rows of one field.
template <class Particles>
Particles read_particle_rows(const hdf5::File& f, const std::string& path, const std::string& group,
                             std::uint64_t count, hdf5::RowRange keep, std::uint64_t rows_per_read, Checksum& c,
                             const char* noun) {
  const std::uint64_t step = rows_per_read == 0 ? std::max<std::uint64_t>(count, 1) : rows_per_read;
  Particles p;
  for_each_restart_field(p, [&](const char* name, auto& field) {
    const std::string dataset = group + "/" + name;
    if (!f.exists(dataset)) throw InputError(fmt::format("{}: {} not found (restart file incomplete)", path, dataset));
    const std::uint64_t rows = f.dataset_info(dataset).rows();
    if (rows != count)
      throw InputError(fmt::format("{}: {} has {} entries, but the file holds {} {} particles", path, dataset, rows,
                                   count, noun));
    if (keep.count < count) field.reserve(keep.count);
    std::remove_reference_t<decltype(field)> run;
    for (std::uint64_t first = 0; first < count; first += step) {
      const hdf5::RowRange range{first, std::min(step, count - first)};
      read_field(f, dataset, run, &range);
      c.add(run);
      const std::uint64_t from = std::max(first, keep.first), to = std::min(first + range.count, keep.first + keep.count);
      if (from == first && to == first + range.count && field.empty()) {
        field = std::move(run);  // the whole run is kept (a whole read): no copy
        run = {};
      } else if (from < to) {
        field.insert(field.end(), run.begin() + static_cast<std::ptrdiff_t>(from - first),
                     run.begin() + static_cast<std::ptrdiff_t>(to - first));
      }
    }
  });
  p.resize(keep.count);  // the fields restart files do not hold
  return p;
}

// Rank r's share of n rows among `ranks`: [n r / ranks, n (r + 1) / ranks), as the initial
// conditions are shared.
hdf5::RowRange share_of_rows(std::uint64_t n, const RestartShare& share) {
  const auto r = static_cast<std::uint64_t>(share.rank), ranks = static_cast<std::uint64_t>(share.ranks);
  const std::uint64_t first = n * r / ranks;
  return {first, n * (r + 1) / ranks - first};
}

}  // namespace

namespace {

void write_scalars(hdf5::File& f, const RestartState& s, std::uint64_t n_gas, std::uint64_t n_dm) {
  f.create_group("/Restart");
  f.write_attribute("/Restart", "FormatVersion", kRestartFormatVersion);
  f.write_attribute("/Restart", "TiCurrent", static_cast<std::int64_t>(s.ti_current));
  f.write_attribute("/Restart", "TiStepBegin", static_cast<std::int64_t>(s.ti_step_begin));
  f.write_attribute("/Restart", "MeshStepBin", static_cast<std::int64_t>(s.mesh_step_bin));
  f.write_attribute("/Restart", "MeshStepBegin", static_cast<std::int64_t>(s.mesh_step_begin));
  f.write_attribute("/Restart", "Steps", static_cast<std::int64_t>(s.steps));
  f.write_attribute("/Restart", "SnapshotsWritten", s.snapshots_written);
  f.write_attribute("/Restart", "NextOutput", s.next_output);
  f.write_attribute("/Restart", "RadiatedEnergy", s.radiated_energy);
  f.write_attribute("/Restart", "NextParticleId", std::vector<std::uint64_t>{s.next_particle_id});
  f.write_attribute("/Restart", "StarFormationTally", tally_values(s.star_formation));
  f.write_attribute("/Restart", "GasParticles", static_cast<std::int64_t>(n_gas));
  f.write_attribute("/Restart", "CollisionlessParticles", static_cast<std::int64_t>(n_dm));
  f.write_string_dataset("/Restart/Parameters", s.parameters_yaml.empty() ? std::string("{}") : s.parameters_yaml);
}

// A master's: its scalars, totals, serial, piece names and parameters.
std::string master_checksum(const RestartState& s, std::uint64_t n_gas, std::uint64_t n_dm, long long serial,
                            const std::string& names) {
  Checksum c;
  const std::string scalars = scalars_checksum_text(s, s.gas.size(), s.dm.size()) +
                              fmt::format(" {} {} {} {}", n_gas, n_dm, serial, names);
  c.add(scalars.data(), scalars.size());
  c.add(s.parameters_yaml.data(), s.parameters_yaml.size());
  return c.hex();
}

// copy(to, from) for each restart field of `whole` and the same field of `part`.
template <class Particles, class Copy>
void copy_restart_fields(Particles& whole, Particles& part, Copy&& copy) {
  std::vector<const void*> fields;
  for_each_restart_field(part, [&](const char*, auto& field) { fields.push_back(&field); });
  std::size_t f = 0;
  for_each_restart_field(whole, [&](const char*, auto& field) {
    using V = std::decay_t<decltype(field)>;
    copy(field, *static_cast<const V*>(fields[f++]));
  });
}

// Puts each particle of `part` at its index in `whole`, field by field; `filled` counts.
template <class Particles>
void place(Particles& whole, Particles& part, const std::vector<std::uint64_t>& index, std::vector<char>& filled,
           const std::string& piece, const char* noun) {
  for (std::size_t k = 0; k < index.size(); ++k) {
    if (index[k] >= filled.size())
      throw InputError(fmt::format("{}: {} particle index {} is beyond the run's {} particles", piece, noun, index[k],
                                   filled.size()));
    if (filled[index[k]]) throw InputError(fmt::format("{}: {} particle {} is also in another piece", piece, noun, index[k]));
    filled[index[k]] = 1;
  }
  copy_restart_fields(whole, part, [&](auto& to, const auto& from) {
    for (std::size_t k = 0; k < index.size(); ++k) to[index[k]] = from[k];
  });
}

// Appends a piece's particles (their restart fields; the others start at zero, as place's).
template <class Particles>
void append_restart_fields(Particles& whole, Particles& part) {
  const std::size_t at = whole.size();
  whole.resize(at + part.size());
  copy_restart_fields(whole, part, [&](auto& to, const auto& from) {
    std::copy(from.begin(), from.end(), to.begin() + static_cast<std::ptrdiff_t>(at));
  });
}

}  // namespace

void write_restart(const std::string& path, const RestartState& s) { write_restart(path, s, s.gas, s.dm); }

void write_restart(const std::string& path, const RestartState& s, const GasParticles& gas,
                   const CollisionlessParticles& dm) {
  hdf5::write_file_atomically(path, "restart file", [&](hdf5::File& f) {
    write_scalars(f, s, gas.size(), dm.size());
    Checksum c;
    add_scalars_to_checksum(c, s, gas.size(), dm.size());
    write_particles(f, kGasGroup, gas, c);
    write_particles(f, kDarkMatterGroup, dm, c);
    f.write_attribute("/Restart", "Checksum", c.hex());
  });
}

std::string restart_piece_name(const std::string& path, long long serial, int rank) {
  const std::string stem = std::filesystem::path(path).stem().string();
  return fmt::format("{}_{:06d}_rank{}.hdf5", stem, serial, rank);
}

namespace {
void write_piece(const std::string& piece_path, const GasParticles& gas, const std::vector<std::size_t>* gas_rows,
                 const CollisionlessParticles& dm, const std::vector<std::size_t>* dm_rows,
                 const std::vector<std::uint64_t>& gas_index, const std::vector<std::uint64_t>& dm_index) {
  const std::size_t n_gas = gas_rows ? gas_rows->size() : gas.size(), n_dm = dm_rows ? dm_rows->size() : dm.size();
  if (gas_index.size() != n_gas || dm_index.size() != n_dm)
    throw std::logic_error(fmt::format("{}: a restart piece of {} and {} particles with {} and {} places", piece_path,
                                       n_gas, n_dm, gas_index.size(), dm_index.size()));
  hdf5::write_file_atomically(piece_path, "restart piece", [&](hdf5::File& f) {
    f.create_group("/Piece");
    f.write_attribute("/Piece", "FormatVersion", kRestartFormatVersion);
    f.write_attribute("/Piece", "GasParticles", static_cast<std::int64_t>(n_gas));
    f.write_attribute("/Piece", "CollisionlessParticles", static_cast<std::int64_t>(n_dm));
    f.write_dataset("/Piece/GasIndex", gas_index);
    f.write_dataset("/Piece/CollisionlessIndex", dm_index);
    Checksum c;  // in the order read_restart_set checks them
    c.add(gas_index);
    c.add(dm_index);
    write_particles(f, kGasGroup, gas, c, gas_rows);
    write_particles(f, kDarkMatterGroup, dm, c, dm_rows);
    f.write_attribute("/Piece", "Checksum", c.hex());
  });
}
}  // namespace

void write_restart_piece(const std::string& piece_path, const RestartPiece& p) {
  write_piece(piece_path, p.gas, nullptr, p.dm, nullptr, p.gas_index, p.dm_index);
}

void write_restart_piece(const std::string& piece_path, const RestartPieceRows& p) {
  write_piece(piece_path, p.gas, &p.gas_rows, p.dm, &p.dm_rows, p.gas_index, p.dm_index);
}

void write_restart_master(const std::string& path, const RestartState& s, long long serial, int pieces,
                          std::uint64_t gas_total, std::uint64_t dm_total) {
  hdf5::write_file_atomically(path, "restart file", [&](hdf5::File& f) {
    write_scalars(f, s, gas_total, dm_total);
    f.write_attribute("/Restart", "Serial", static_cast<std::int64_t>(serial));
    std::string names;
    for (int r = 0; r < pieces; ++r) names += restart_piece_name(path, serial, r) + "\n";
    f.write_string_dataset("/Restart/Pieces", names);
    f.write_attribute("/Restart", "Checksum", master_checksum(s, gas_total, dm_total, serial, names));
  });
}

namespace {
std::vector<std::string> master_pieces(const std::string& path) {
  std::vector<std::string> names;
  if (!std::filesystem::exists(path) || !hdf5::is_hdf5(path)) return names;
  hdf5::File f(path, hdf5::File::Mode::read);
  if (!f.exists("/Restart/Pieces")) return names;
  const std::string text = f.read_string("/Restart/Pieces");
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = text.find('\n', at);
    names.push_back(text.substr(at, end - at));
    if (end == std::string::npos) break;
    at = end + 1;
  }
  return names;
}
}  // namespace

void remove_stale_restart_pieces(const std::string& path) {
  const std::vector<std::string> keep = master_pieces(path);
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  const std::string prefix = std::filesystem::path(path).stem().string() + "_";
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir.empty() ? "." : dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0 || name.find("_rank") == std::string::npos || entry.path().extension() != ".hdf5")
      continue;
    if (std::find(keep.begin(), keep.end(), name) == keep.end()) std::filesystem::remove(entry.path(), ec);
  }
}

namespace {
RestartState read_restart_set(const hdf5::File& f, const std::string& path, RestartState s, std::uint64_t n_gas,
                              std::uint64_t n_dm, const RestartShare& share) {
  if (!f.has_attribute("/Restart", "Serial"))
    throw InputError(fmt::format("{}: /Restart has no attribute Serial (restart file incomplete)", path));
  s.serial = f.read_attribute_int64("/Restart", "Serial").at(0);
  const std::string names = f.read_string("/Restart/Pieces");
  const std::string stored = f.read_attribute_string("/Restart", "Checksum");
  if (stored != master_checksum(s, n_gas, n_dm, s.serial, names))
    throw InputError(fmt::format("{}: restart file is corrupted (checksum {} does not match its contents)", path, stored));
  const bool shared = share.ranks > 1;
  s.gas_total = n_gas;
  s.dm_total = n_dm;
  s.gas_shared = shared;
  if (!shared) {
    s.gas.resize(n_gas);
    s.dm.resize(n_dm);
  }
  std::vector<char> gas_filled(shared ? 0 : n_gas, 0), dm_filled(shared ? 0 : n_dm, 0);
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  const std::vector<std::string> pieces = master_pieces(path);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    if (shared && static_cast<int>(k % static_cast<std::size_t>(share.ranks)) != share.rank) continue;
    const std::string& name = pieces[k];
    const std::string piece = (dir / name).string();
    if (!std::filesystem::exists(piece))
      throw InputError(fmt::format("{}: restart piece {} named by {} is missing", piece, name, path));
    if (!hdf5::is_hdf5(piece)) throw InputError(fmt::format("{}: not a restart piece (not HDF5, or truncated)", piece));
    hdf5::File pf(piece, hdf5::File::Mode::read);
    for (const char* a : {"FormatVersion", "GasParticles", "CollisionlessParticles", "Checksum"})
      if (!pf.exists("/Piece") || !pf.has_attribute("/Piece", a))
        throw InputError(fmt::format("{}: /Piece has no attribute {} (restart piece incomplete)", piece, a));
    RestartPiece p;
    const std::uint64_t pg = pf.read_attribute_uint64("/Piece", "GasParticles").at(0);
    const std::uint64_t pd = pf.read_attribute_uint64("/Piece", "CollisionlessParticles").at(0);
    p.gas_index = pf.read_uint64("/Piece/GasIndex");
    p.dm_index = pf.read_uint64("/Piece/CollisionlessIndex");
    if (p.gas_index.size() != pg || p.dm_index.size() != pd)
      throw InputError(fmt::format("{}: its particle indices disagree with its particle counts", piece));
    Checksum c;  // in the order write_piece adds them
    c.add(p.gas_index);
    c.add(p.dm_index);
    p.gas = read_particle_rows<GasParticles>(pf, piece, kGasGroup, pg, {0, pg}, 0, c, "gas");
    p.dm = read_particle_rows<CollisionlessParticles>(pf, piece, kDarkMatterGroup, pd, {0, pd}, 0, c, "collisionless");
    const std::string stored = pf.read_attribute_string("/Piece", "Checksum");
    if (stored != c.hex())
      throw InputError(fmt::format("{}: restart piece is corrupted (checksum {} does not match its contents)", piece, stored));
    if (shared) {
      for (std::uint64_t i : p.gas_index)
        if (i >= n_gas) throw InputError(fmt::format("{}: holds the place {} of a run of {} gas particles", piece, i, n_gas));
      for (std::uint64_t i : p.dm_index)
        if (i >= n_dm)
          throw InputError(fmt::format("{}: holds the place {} of a run of {} collisionless particles", piece, i, n_dm));
      append_restart_fields(s.gas, p.gas);
      append_restart_fields(s.dm, p.dm);
      s.gas_places.insert(s.gas_places.end(), p.gas_index.begin(), p.gas_index.end());
      s.dm_places.insert(s.dm_places.end(), p.dm_index.begin(), p.dm_index.end());
      continue;
    }
    place(s.gas, p.gas, p.gas_index, gas_filled, piece, "gas");
    place(s.dm, p.dm, p.dm_index, dm_filled, piece, "collisionless");
  }
  if (shared) return s;
  const auto missing = [](const std::vector<char>& v) { return std::count(v.begin(), v.end(), 0); };
  if (missing(gas_filled) > 0 || missing(dm_filled) > 0)
    throw InputError(fmt::format("{}: its pieces hold {} of {} gas and {} of {} collisionless particles", path,
                                 n_gas - static_cast<std::uint64_t>(missing(gas_filled)), n_gas,
                                 n_dm - static_cast<std::uint64_t>(missing(dm_filled)), n_dm));
  return s;
}
}  // namespace

RestartState read_restart(const std::string& path) { return read_restart(path, RestartShare{}); }

RestartState read_restart(const std::string& path, const RestartShare& share) {
  if (!std::filesystem::exists(path)) throw InputError(fmt::format("{}: no such restart file", path));
  if (!hdf5::is_hdf5(path)) throw InputError(fmt::format("{}: not a restart file (not HDF5, or truncated)", path));
  hdf5::File f(path, hdf5::File::Mode::read);
  if (!f.exists("/Restart") || !f.has_attribute("/Restart", "FormatVersion"))
    throw InputError(fmt::format("{}: not a Fountain restart file", path));
  const auto version = static_cast<int>(f.read_attribute_double("/Restart", "FormatVersion"));
  if (version != kRestartFormatVersion)
    throw InputError(fmt::format("{}: restart format version {} cannot be read by this build (it reads version {})",
                                 path, version, kRestartFormatVersion));
  for (const char* name : {"TiCurrent", "TiStepBegin", "MeshStepBin", "MeshStepBegin", "Steps", "SnapshotsWritten", "NextOutput", "RadiatedEnergy", "NextParticleId",
                           "StarFormationTally", "GasParticles", "CollisionlessParticles", "Checksum"})
    if (!f.has_attribute("/Restart", name))
      throw InputError(fmt::format("{}: /Restart has no attribute {} (restart file incomplete)", path, name));
  RestartState s;
  s.ti_current = f.read_attribute_int64("/Restart", "TiCurrent").at(0);
  s.ti_step_begin = f.read_attribute_int64("/Restart", "TiStepBegin").at(0);
  s.mesh_step_bin = static_cast<int>(f.read_attribute_int64("/Restart", "MeshStepBin").at(0));
  s.mesh_step_begin = f.read_attribute_int64("/Restart", "MeshStepBegin").at(0);
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
  if (f.exists("/Restart/Pieces")) return read_restart_set(f, path, std::move(s), n_gas, n_dm, share);
  s.gas_total = n_gas;
  s.dm_total = n_dm;
  // Across ranks each keeps its rows, and reads the rest a run of rows at a time for the
  // checksum only.
  const bool shared = share.ranks > 1;
  const hdf5::RowRange gas_rows = shared ? share_of_rows(n_gas, share) : hdf5::RowRange{0, n_gas};
  const hdf5::RowRange dm_rows = shared ? share_of_rows(n_dm, share) : hdf5::RowRange{0, n_dm};
  const std::uint64_t run = shared ? std::max<std::uint64_t>(share.rows_per_read, 1) : 0;
  Checksum c;
  add_scalars_to_checksum(c, s, n_gas, n_dm);
  s.gas = read_particle_rows<GasParticles>(f, path, kGasGroup, n_gas, gas_rows, run, c, "gas");
  s.dm = read_particle_rows<CollisionlessParticles>(f, path, kDarkMatterGroup, n_dm, dm_rows, run, c, "collisionless");
  const std::string stored = f.read_attribute_string("/Restart", "Checksum");
  if (stored != c.hex())
    throw InputError(fmt::format("{}: restart file is corrupted (checksum {} does not match its contents)", path, stored));
  s.gas_shared = s.read_as_rows = shared;
  s.gas_first = gas_rows.first;
  s.dm_first = dm_rows.first;
  return s;
}

}  // namespace fountain::io
