// Each particle field reaches the snapshots, restart files and MPI messages its row of the table names; the user guide lists the table's datasets.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <set>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "TempDirTest.hpp"
#include "engine/CellMessages.hpp"
#include "io/FieldDatasets.hpp"
#include "io/Hdf5File.hpp"
#include "io/RestartFile.hpp"
#include "io/Snapshot.hpp"
#include "particles/ParticleFields.hpp"
#include "space/Space.hpp"

namespace fountain {
namespace {

using io::hdf5::File;

class ParticleFields : public testing::TempDirTest {};

// Every value of every field distinct from the others (as far as the type allows) and not
// round in binary; `salt` makes two stores differ everywhere. Stars are every third
// collisionless particle.
template <class Store>
void fill_distinct(Store& s, double salt) {
  int k = 0;
  for_each_field_of(s, [&](const FieldInfo&, auto& values) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const double x = 1000.0 * k + static_cast<double>(i) + 0.1 * salt + 1.0 / 3.0;
      if constexpr (std::is_same_v<T, Vec3>) values[i] = {x, -x / 7.0, x * 1e-9};
      else if constexpr (std::is_same_v<T, double>) values[i] = -x;
      else if constexpr (std::is_same_v<T, Species>) values[i] = i % 3 == 0 ? Species::Star : Species::DarkMatter;
      else if constexpr (sizeof(T) == 1) values[i] = static_cast<T>(static_cast<long long>(x) % 100);  // bins, flags
      else values[i] = static_cast<T>(x);  // ids, integer times
    }
    ++k;
  });
}

// A field as bytes, to compare any two stores' copies of it particle by particle.
struct FieldBytes {
  FieldInfo info;
  const char* data;
  std::size_t size;  // of one value
  bool same(const FieldBytes& o, std::size_t i) const { return std::memcmp(data + i * size, o.data + i * size, size) == 0; }
};
template <class Store>
std::vector<FieldBytes> bytes_of(const Store& s) {
  std::vector<FieldBytes> out;
  for_each_field_of(s, [&](const FieldInfo& info, const auto& values) {
    out.push_back({info, reinterpret_cast<const char*>(values.data()), sizeof(values[0])});
  });
  return out;
}

// The links in an HDF5 group.
std::size_t links_in(const File& f, const std::string& group) {
  const hid_t g = H5Gopen2(f.id(), group.c_str(), H5P_DEFAULT);
  H5G_info_t info{};
  const herr_t status = H5Gget_info(g, &info);
  H5Gclose(g);
  return status < 0 ? 0 : static_cast<std::size_t>(info.nlinks);
}

bool written(InSnapshots when, bool star_formation, bool stars) {
  return when == InSnapshots::always || (when == InSnapshots::with_star_formation && star_formation) ||
         (when == InSnapshots::stars_only && stars);
}

// The field's values of the particles `pick`, compared with what the dataset holds; and the
// dataset's unit attributes, compared with the table's.
template <class T>
void expect_dataset(const File& f, const std::string& dataset, const FieldInfo& field, const std::vector<T>& values,
                    const std::vector<std::size_t>& pick, const io::SnapshotInfo& info) {
  std::vector<T> expected, got;
  for (std::size_t i : pick) expected.push_back(values[i]);
  io::read_field(f, dataset, got);
  ASSERT_EQ(got.size(), expected.size()) << dataset;
  EXPECT_EQ(std::memcmp(got.data(), expected.data(), got.size() * sizeof(T)), 0) << dataset << " holds other values";
  const Dimensions& d = field.units;
  EXPECT_EQ(f.read_attribute_doubles(dataset, "U_M exponent"), std::vector<double>{d.mass}) << dataset;
  EXPECT_EQ(f.read_attribute_doubles(dataset, "U_L exponent"), std::vector<double>{d.length}) << dataset;
  EXPECT_EQ(f.read_attribute_doubles(dataset, "U_t exponent"), std::vector<double>{d.time}) << dataset;
  EXPECT_EQ(f.read_attribute_doubles(dataset, "a-scale exponent"), std::vector<double>{a_power(d, info.gamma)})
      << dataset;
  const double cgs = std::pow(info.units.mass_cgs, d.mass) * std::pow(info.units.length_cgs, d.length) *
                     std::pow(info.units.time_cgs(), d.time);
  EXPECT_EQ(f.read_attribute_doubles(dataset, "Conversion factor to CGS (not including cosmological corrections)"),
            std::vector<double>{cgs})
      << dataset;
  EXPECT_EQ(f.read_attribute_string(dataset, "Expression for physical CGS units"), io::unit_expression(d)) << dataset;
  EXPECT_EQ(f.read_attribute_string(dataset, "Description"), field.description) << dataset;
}

// Every field the table flags for the group is there with its values and units, and nothing
// else but the datasets worked out at write time (`computed`).
template <class Store>
void expect_group(const File& f, const std::string& group, const Store& p, const std::vector<std::size_t>& pick,
                  const io::SnapshotInfo& info, bool stars, std::size_t computed) {
  std::size_t fields = 0;
  for_each_field_of(p, [&](const FieldInfo& field, const auto& values) {
    const std::string dataset = group + "/" + field.name;
    if (!written(field.snapshot, info.star_formation, stars)) {
      EXPECT_FALSE(f.exists(dataset)) << dataset << " is not flagged for this snapshot";
      return;
    }
    ++fields;
    ASSERT_TRUE(f.exists(dataset)) << dataset << " is flagged but missing";
    expect_dataset(f, dataset, field, values, pick, info);
  });
  EXPECT_EQ(links_in(f, group), fields + computed) << group << " holds datasets the table does not name";
}

io::SnapshotInfo snapshot_info(bool star_formation) {
  io::SnapshotInfo info;
  info.time = 0.5;
  info.box_size = {1.0e6, 1.0e6, 1.0e6};  // open: positions are written as they are
  info.units = Units{};
  info.gamma = 1.4;  // the a-powers of u and P depend on it
  info.temperature = [](double u) { return 2.0 * u; };
  info.star_formation = star_formation;
  return info;
}

std::vector<std::size_t> all_of(std::size_t n) {
  std::vector<std::size_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = i;
  return v;
}

TEST_F(ParticleFields, SnapshotsHoldEveryFlaggedFieldWithItsValuesAndUnits) {
  GasParticles gas;
  CollisionlessParticles dm;
  gas.resize(11);
  dm.resize(13);
  fill_distinct(gas, 1.0);
  fill_distinct(dm, 2.0);
  std::vector<std::size_t> dark, stars;
  for (std::size_t i = 0; i < dm.size(); ++i) (dm.species[i] == Species::Star ? stars : dark).push_back(i);
  ASSERT_FALSE(dark.empty());
  ASSERT_FALSE(stars.empty());
  for (const bool star_formation : {false, true}) {
    SCOPED_TRACE(star_formation ? "with star formation" : "without star formation");
    const io::SnapshotInfo info = snapshot_info(star_formation);
    const std::string path = file(star_formation ? "sf.hdf5" : "plain.hdf5");
    io::write_snapshot(path, gas, dm, info);
    const File f(path, File::Mode::read);
    expect_group(f, "/PartType0", gas, all_of(gas.size()), info, false, 2);
    expect_group(f, "/PartType1", dm, dark, info, false, 0);
    expect_group(f, "/PartType4", dm, stars, info, true, 0);
    EXPECT_TRUE(f.exists(std::string("/PartType0/") + io::kPressureDataset.name));
    EXPECT_TRUE(f.exists(std::string("/PartType0/") + io::kTemperatureDataset.name));
  }
}

TEST_F(ParticleFields, RestartFilesRestoreEveryFlaggedField) {
  io::RestartState s;
  s.gas.resize(9);
  s.dm.resize(7);
  fill_distinct(s.gas, 3.0);
  fill_distinct(s.dm, 4.0);
  s.gas.potential[2] = -0.0;  // the sign of zero too
  const std::string path = file("restart.hdf5");
  io::write_restart(path, s);
  const io::RestartState r = io::read_restart(path);

  auto expect_restored = [&](const auto& written_store, const auto& read_store, const std::string& group) {
    ASSERT_EQ(read_store.size(), written_store.size()) << group;
    const auto before = bytes_of(written_store), after = bytes_of(read_store);
    const File f(path, File::Mode::read);
    std::size_t flagged = 0;
    for (std::size_t k = 0; k < before.size(); ++k) {
      const FieldInfo& field = before[k].info;
      EXPECT_EQ(f.exists(group + "/" + field.key), field.restart) << group << "/" << field.key;
      if (!field.restart) continue;
      ++flagged;
      for (std::size_t i = 0; i < written_store.size(); ++i)
        EXPECT_TRUE(before[k].same(after[k], i)) << group << "/" << field.key << " of particle " << i;
    }
    EXPECT_EQ(links_in(f, group), flagged) << group << " holds datasets the table does not flag";
  };
  expect_restored(s.gas, r.gas, "/Gas");
  expect_restored(s.dm, r.dm, "/DarkMatter");
}

// ---- MPI messages -----------------------------------------------------------------------------

// Two ranks' copies of a space's particles, different in every byte of every field.
struct Ranks {
  GasParticles gas;
  CollisionlessParticles dm;
  Space space{SpaceConfig{}};
  Ranks() {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    gas.resize(500);
    dm.resize(250);
    for (auto& x : gas.x) x = {u(rng), u(rng), u(rng)};
    for (auto& x : dm.x) x = {u(rng), u(rng), u(rng)};
    for (double& h : gas.h) h = 0.05;
    SpaceConfig c;
    c.split_size = 64;
    space = Space(c);
    space.rebuild(gas, dm);
  }
};

template <class Store>
void scramble(Store& s, unsigned seed) {
  std::mt19937_64 rng(seed);
  for_each_field_of(s, [&](const FieldInfo&, auto& values) {
    for (auto& v : values) {
      unsigned char bytes[sizeof(v)];
      for (auto& b : bytes) b = static_cast<unsigned char>(rng());
      std::memcpy(&v, bytes, sizeof(v));
    }
  });
}

// After a message from `sent` to `got` (which held `before`): the particles [first, first +
// count) hold the sender's values in exactly the fields flagged `parts`, and their own in
// every other.
template <class Store>
void expect_carried(const Store& sent, const Store& got, const Store& before, std::size_t first, std::size_t count,
                    Messages parts, const char* message) {
  const auto s = bytes_of(sent), g = bytes_of(got), b = bytes_of(before);
  for (std::size_t k = 0; k < s.size(); ++k) {
    const bool flagged = (s[k].info.messages & parts) != 0;
    for (std::size_t i = first; i < first + count; ++i) {
      if (flagged) EXPECT_TRUE(g[k].same(s[k], i)) << message << " does not carry " << s[k].info.key << " of " << i;
      else EXPECT_TRUE(g[k].same(b[k], i)) << message << " carries " << s[k].info.key << " of " << i;
    }
  }
}

TEST_F(ParticleFields, EachMessageCarriesExactlyTheFlaggedFields) {
  const Ranks ranks;
  const Space& space = ranks.space;
  const int c = space.leaves()[space.leaves().size() / 2];
  const Cell& cell = space.cell(c);
  ASSERT_GT(cell.count, 0u);
  ASSERT_GT(cell.dm_count, 0u);
  const std::vector<char> gas_all(ranks.gas.size(), 1), dm_all(ranks.dm.size(), 1);
  std::vector<std::size_t> leaf_gas;
  for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) leaf_gas.push_back(i);
  std::vector<std::size_t> leaf_dm;
  for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) leaf_dm.push_back(i);
  using namespace message;
  constexpr Messages ghost = ghost_density | ghost_bin | ghost_force_inputs;

  struct Case {
    const char* name;
    Messages gas_parts, dm_parts;
    std::size_t header;  // bytes before the fields
    std::function<void(MessageWriter&, Space&, GasParticles&, CollisionlessParticles&)> pack;
    std::function<void(MessageReader&, Space&, GasParticles&, CollisionlessParticles&)> unpack;
  };
  const std::vector<Case> cases{
      {"the whole state", whole_state, whole_state, sizeof(Cell),
       [&](auto& w, auto& sp, auto& g, auto& d) { pack_cell_state(w, sp, g, d, c, gas_all, dm_all, StateFields::All); },
       [&](auto& r, auto& sp, auto& g, auto& d) { unpack_cell_state(r, sp, g, d, c, gas_all, dm_all, StateFields::All); }},
      {"the step's state", step_state, step_state, sizeof(Cell),
       [&](auto& w, auto& sp, auto& g, auto& d) {
         pack_cell_state(w, sp, g, d, c, gas_all, dm_all, StateFields::StepChanged);
       },
       [&](auto& r, auto& sp, auto& g, auto& d) {
         unpack_cell_state(r, sp, g, d, c, gas_all, dm_all, StateFields::StepChanged);
       }},
      {"the ghost's results", ghost, 0, sizeof(double),
       [&](auto& w, auto& sp, auto& g, auto&) { pack_ghost_results(w, sp, g, c); },
       [&](auto& r, auto& sp, auto& g, auto&) { unpack_ghost_results(r, sp, g, c); }},
      {"halo mode's changed gas", ghost_density | halo_after_ghost, 0, 0,
       [&](auto& w, auto& sp, auto& g, auto&) { pack_moved_gas(w, sp, g, c, gas_all); },
       [&](auto& r, auto& sp, auto& g, auto&) { unpack_moved_gas(r, sp, g, c, gas_all); }},
      {"halo mode's changed gas after a ghost message", halo_after_ghost, 0, 0,
       [&](auto& w, auto& sp, auto& g, auto&) { pack_moved_gas(w, sp, g, c, gas_all, true); },
       [&](auto& r, auto& sp, auto& g, auto&) { unpack_moved_gas(r, sp, g, c, gas_all, true); }},
      {"migrating particles", migration, 0, 0,
       [&](auto& w, auto&, auto& g, auto&) { pack_particles(w, g, leaf_gas); },
       [&](auto& r, auto&, auto& g, auto&) { unpack_particles(r, g, leaf_gas); }},
      {"migrating collisionless particles", 0, migration, 0,
       [&](auto& w, auto&, auto&, auto& d) { pack_particles(w, d, leaf_dm); },
       [&](auto& r, auto&, auto&, auto& d) { unpack_particles(r, d, leaf_dm); }},
  };
  unsigned seed = 10;
  for (const Case& m : cases) {
    Space sender_space = space, receiver_space = space;
    GasParticles sent_gas = ranks.gas, got_gas = ranks.gas;
    CollisionlessParticles sent_dm = ranks.dm, got_dm = ranks.dm;
    scramble(sent_gas, seed++);
    scramble(got_gas, seed++);
    scramble(sent_dm, seed++);
    scramble(got_dm, seed++);
    const GasParticles gas_before = got_gas;
    const CollisionlessParticles dm_before = got_dm;
    std::vector<char> buffer;
    MessageWriter w(buffer);
    m.pack(w, sender_space, sent_gas, sent_dm);
    EXPECT_EQ(buffer.size(), m.header + cell.count * bytes_per_particle_in<GasParticles>(m.gas_parts) +
                                 cell.dm_count * bytes_per_particle_in<CollisionlessParticles>(m.dm_parts))
        << m.name << ": its size is not the flagged fields'";
    MessageReader r(buffer);
    m.unpack(r, receiver_space, got_gas, got_dm);
    EXPECT_TRUE(r.done()) << m.name << " holds more than its reader took";
    expect_carried(sent_gas, got_gas, gas_before, cell.first, cell.count, m.gas_parts, m.name);
    expect_carried(sent_dm, got_dm, dm_before, cell.dm_first, cell.dm_count, m.dm_parts, m.name);
  }
}

// ---- The table itself and the user guide ----------------------------------------------------------

template <class Store>
void expect_sound_table(const char* store) {
  std::set<std::string> keys, names;
  const Store none;
  for_each_field_of(none, [&](const FieldInfo& field, const auto&) {
    EXPECT_TRUE(keys.insert(field.key).second) << store << ": key " << field.key << " twice";
    EXPECT_TRUE(names.insert(field.name).second) << store << ": name " << field.name << " twice";
    if (field.snapshot != InSnapshots::never) {
      EXPECT_FALSE(field.units.depends_on_parameters) << store << ": " << field.key << " has no fixed units to write";
    }
    if ((field.messages & message::step_state) != 0) {
      EXPECT_NE(field.messages & message::whole_state, 0)
          << store << ": " << field.key << " is in the step's state but not the whole state";
    }
  });
}

TEST(ParticleFieldTable, KeysAndNamesAreUniqueAndSnapshotFieldsHaveUnits) {
  expect_sound_table<GasParticles>("gas");
  expect_sound_table<CollisionlessParticles>("collisionless");
}

// The power of a as the user guide writes it: "1", "-3 gamma", "-3 (gamma - 1)".
std::string a_power_text(const Dimensions& d) {
  std::vector<std::string> terms;
  if (d.a != 0.0) terms.push_back(fmt::format("{}", d.a));
  if (d.a_gamma != 0.0) terms.push_back(fmt::format("{} gamma", d.a_gamma));
  if (d.a_gamma_minus_1 != 0.0) terms.push_back(fmt::format("{} (gamma - 1)", d.a_gamma_minus_1));
  if (terms.empty()) return "0";
  std::string text = terms[0];
  for (std::size_t k = 1; k < terms.size(); ++k) text += " + " + terms[k];
  return text;
}

std::string row(const std::string& group, const char* name, const Dimensions& units, const char* written,
                const char* description) {
  return fmt::format("| {} | `{}` | `{}` | {} | {} | {} |", group, name, io::unit_expression(units),
                     a_power_text(units), written, description);
}

// The user guide's table of snapshot datasets, as the table of particle fields gives it.
std::vector<std::string> dataset_rows() {
  std::vector<std::string> rows{"| Group | Dataset | Units | Power of a | Written | Description |",
                                "|---|---|---|---|---|---|"};
  GasParticles gas;
  for_each_field_of(gas, [&](const FieldInfo& f, const auto&) {
    if (f.snapshot == InSnapshots::always) rows.push_back(row("PartType0", f.name, f.units, "always", f.description));
    if (f.snapshot == InSnapshots::with_star_formation)
      rows.push_back(row("PartType0", f.name, f.units, "with star formation", f.description));
  });
  for (const io::ComputedDataset& d : {io::kPressureDataset, io::kTemperatureDataset})
    rows.push_back(row("PartType0", d.name, d.units, "always", d.description));
  CollisionlessParticles dm;
  for_each_field_of(dm, [&](const FieldInfo& f, const auto&) {
    if (f.snapshot == InSnapshots::always)
      rows.push_back(row("PartType1, PartType4", f.name, f.units, "always", f.description));
    if (f.snapshot == InSnapshots::stars_only)
      rows.push_back(row("PartType4", f.name, f.units, "always", f.description));
  });
  return rows;
}

TEST(ParticleFieldTable, UserGuideListsEverySnapshotDataset) {
  const std::string path = std::string(FOUNTAIN_SOURCE_DIR) + "/docs/user_guide.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path << " is missing";
  const std::string begin = "<!-- snapshot datasets", end = "<!-- end of snapshot datasets";
  std::vector<std::string> listed;
  int state = 0;  // 0: before the list, 1: in it, 2: after it
  for (std::string line; std::getline(in, line);) {
    if (state == 0 && line.rfind(begin, 0) == 0) state = 1;
    else if (state == 1 && line.rfind(end, 0) == 0) state = 2;
    else if (state == 1) listed.push_back(line);
  }
  ASSERT_EQ(state, 2) << path << " has no list between lines starting '" << begin << "' and '" << end << "'";
  const std::vector<std::string> expected = dataset_rows();
  if (listed == expected) return;
  std::string message = "docs/user_guide.md's list of snapshot datasets is not the table's "
                        "(src/particles/ParticleFields.hpp, io/Snapshot.hpp).\n";
  for (const std::string& r : expected)
    if (std::find(listed.begin(), listed.end(), r) == listed.end()) message += "  missing from the guide: " + r + "\n";
  for (const std::string& r : listed)
    if (std::find(expected.begin(), expected.end(), r) == expected.end()) message += "  not in the table:      " + r + "\n";
  message += "The list as the table gives it, to put between the two marker lines:\n";
  for (const std::string& r : expected) message += r + "\n";
  ADD_FAILURE() << message;
}

}  // namespace
}  // namespace fountain
