// Tests of the HDF5 initial-conditions reader/writer and of the snapshot writer.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "TempDirTest.hpp"
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "app/Simulation.hpp"
#include "core/Error.hpp"
#include "engine/RunConfig.hpp"
#include "io/Hdf5File.hpp"
#include "io/InitialConditions.hpp"
#include "io/RestartFile.hpp"
#include "io/Snapshot.hpp"
#include "params/ParameterFile.hpp"

namespace fs = std::filesystem;
using fountain::CollisionlessParticles;
using fountain::GasParticles;
using fountain::InputError;
using fountain::Vec3;
using fountain::io::hdf5::File;

namespace {

// Every test gets its own empty folder, removed afterwards.
class IoTest : public fountain::testing::TempDirTest {};

GasParticles make_gas(std::size_t n, std::uint64_t first_id = 1) {
  GasParticles gas;
  gas.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i);
    gas.id[i] = first_id + i;
    gas.mass[i] = 1.0 + 0.01 * s;
    gas.x[i] = {std::fmod(0.37 * s, 2.0), 1.0 + 0.9 * std::sin(s), 1.0 / (s + 3.0)};  // inside [0, 2)^3
    gas.v_full[i] = {-s, 0.5 * s, 1e-7 * s};
    gas.v[i] = gas.v_full[i];
    gas.u_full[i] = 2.5 + s * s;
    gas.u[i] = gas.u_full[i];
    gas.h[i] = 0.3 + 1e-3 * s;
    gas.rho[i] = 10.0 + s;
    gas.wcount[i] = 32.0 + 0.1 * s;
    gas.time_bin[i] = static_cast<fountain::TimeBin>(i % 5);
  }
  return gas;
}

CollisionlessParticles make_dm(std::size_t n, std::uint64_t first_id = 100000) {
  CollisionlessParticles dm;
  dm.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i);
    dm.id[i] = first_id + 3 * i;
    dm.mass[i] = 7.0 + 0.125 * s;
    dm.x[i] = {std::fmod(0.53 * s, 2.0), 1.0 + 0.8 * std::cos(s), 0.5 + 1.0 / (s + 2.0)};
    dm.v_full[i] = {0.25 * s, -s, 3e-6 * s};
    dm.v[i] = dm.v_full[i] * 0.5;
  }
  return dm;
}

// A GADGET-layout file written field by field, so tests can leave things out or break them.
struct HandWritten {
  std::vector<std::uint64_t> ids;
  std::vector<Vec3> x, v;
  std::vector<double> mass, u;
  bool write_masses = true;
  bool write_energy = true;
  std::vector<double> mass_table = std::vector<double>(6, 0.0);
  long long header_count = -1;  // -1: the number of IDs
  // Dark matter (/PartType1), written when dm_ids is not empty or dm_header_count > 0.
  std::vector<std::uint64_t> dm_ids;
  std::vector<Vec3> dm_x, dm_v;
  std::vector<double> dm_mass;
  bool write_dm_masses = true;
  bool write_dm_group = true;
  long long dm_header_count = -1;  // -1: the number of dark matter IDs
};

HandWritten hand_written(std::size_t n, std::size_t n_dm = 0) {
  const GasParticles gas = make_gas(n);
  HandWritten h;
  h.ids = gas.id;
  h.x = gas.x;
  h.v = gas.v_full;
  h.mass = gas.mass;
  h.u = gas.u_full;
  const CollisionlessParticles dm = make_dm(n_dm);
  h.dm_ids = dm.id;
  h.dm_x = dm.x;
  h.dm_v = dm.v_full;
  h.dm_mass = dm.mass;
  return h;
}

void write_by_hand(const std::string& path, const HandWritten& h) {
  File f(path, File::Mode::create);
  f.create_group("/Header");
  const auto n = static_cast<std::int32_t>(h.header_count >= 0 ? h.header_count : static_cast<long long>(h.ids.size()));
  const auto n_dm = static_cast<std::int32_t>(h.dm_header_count >= 0 ? h.dm_header_count
                                                                      : static_cast<long long>(h.dm_ids.size()));
  // int32 counts and a 64-bit total, as different IC generators write them.
  f.write_attribute("/Header", "NumPart_ThisFile", std::vector<std::int32_t>{n, n_dm, 0, 0, 0, 0});
  f.write_attribute("/Header", "NumPart_Total", std::vector<std::uint64_t>{static_cast<std::uint64_t>(n),
                                                                           static_cast<std::uint64_t>(n_dm), 0, 0, 0, 0});
  f.write_attribute("/Header", "MassTable", h.mass_table);
  f.write_attribute("/Header", "BoxSize", 4.0);  // scalar: a cube; no Time attribute
  f.create_group("/PartType0");
  f.write_dataset("/PartType0/ParticleIDs", h.ids);
  f.write_dataset("/PartType0/Coordinates", h.x);
  f.write_dataset("/PartType0/Velocities", h.v);
  if (h.write_masses) f.write_dataset("/PartType0/Masses", h.mass);
  if (h.write_energy) f.write_dataset("/PartType0/InternalEnergy", h.u);
  if ((!h.dm_ids.empty() || n_dm > 0) && h.write_dm_group) {
    f.create_group("/PartType1");
    f.write_dataset("/PartType1/ParticleIDs", h.dm_ids);
    f.write_dataset("/PartType1/Coordinates", h.dm_x);
    f.write_dataset("/PartType1/Velocities", h.dm_v);
    if (h.write_dm_masses) f.write_dataset("/PartType1/Masses", h.dm_mass);
  }
  f.close();
}

// Runs `fn`, expects InputError, returns its message.
template <class Fn>
std::string error_of(Fn fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got another exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected InputError, nothing was thrown";
  return "";
}

// Writes `h` to `path` by hand and returns the InputError that reading it as ICs gives.
std::string read_error(const std::string& path, const HandWritten& h) {
  write_by_hand(path, h);
  return error_of([&] { fountain::io::read_initial_conditions(path); });
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

fountain::io::SnapshotInfo snapshot_info() {
  fountain::io::SnapshotInfo info;
  info.time = 0.125;
  info.step = 42;
  info.box_size = {2.0, 2.0, 2.0};
  info.periodic = true;
  info.units.length_cgs = 3.0856775814913673e21;  // kpc
  info.units.mass_cgs = 1.988409870698051e43;     // 1e10 Msun
  info.units.velocity_cgs = 1e5;
  info.gamma = 5.0 / 3.0;
  info.parameters_yaml =
      "hydro:\n  gamma: 1.6666666666666667\n  neighbours: 32\noutput:\n  basename: snap\n"
      "  directory: \"out: put\"\nrun:\n  t_end: 1\n";
  info.git_revision = "0123456789ab";
  info.build_options = "Release -O3";
  return info;
}

}  // namespace

// ---- Initial conditions ---------------------------------------------------------------------

TEST_F(IoTest, InitialConditionsRoundTripIsExact) {
  const GasParticles gas = make_gas(37, 1000);
  const std::string path = file("ics.hdf5");
  fountain::io::write_initial_conditions(path, gas, {1.5, 2.5, 3.5}, true, 0.75);
  EXPECT_FALSE(fs::exists(path + ".tmp"));

  const auto ic = fountain::io::read_initial_conditions(path);
  ASSERT_EQ(ic.gas.size(), gas.size());
  EXPECT_EQ(ic.box_size, (Vec3{1.5, 2.5, 3.5}));
  EXPECT_EQ(ic.time, 0.75);
  EXPECT_TRUE(ic.has_smoothing_length);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    EXPECT_EQ(ic.gas.id[i], gas.id[i]);
    EXPECT_EQ(ic.gas.mass[i], gas.mass[i]);
    EXPECT_EQ(ic.gas.x[i], gas.x[i]);
    EXPECT_EQ(ic.gas.v_full[i], gas.v_full[i]);
    EXPECT_EQ(ic.gas.v[i], gas.v_full[i]);
    EXPECT_EQ(ic.gas.u_full[i], gas.u_full[i]);
    EXPECT_EQ(ic.gas.u[i], gas.u_full[i]);
    EXPECT_EQ(ic.gas.h[i], gas.h[i]);
    EXPECT_EQ(ic.gas.time_bin[i], 0);
  }

  // The header is GADGET-2 compatible.
  File f(path, File::Mode::read);
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_ThisFile"), (std::vector<std::uint64_t>{37, 0, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_Total_HighWord"),
            (std::vector<std::uint64_t>{0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_doubles("/Header", "MassTable"), std::vector<double>(6, 0.0));
  EXPECT_EQ(f.read_attribute_int64("/Header", "Periodic"), std::vector<std::int64_t>{1});
  EXPECT_EQ(f.dataset_info("/PartType0/ParticleIDs").type_class, H5T_INTEGER);
}

TEST_F(IoTest, MissingFileIsAnError) {
  const std::string path = file("nope.hdf5");
  const std::string msg = error_of([&] { fountain::io::read_initial_conditions(path); });
  EXPECT_TRUE(contains(msg, path)) << msg;
  EXPECT_TRUE(contains(msg, "not found")) << msg;
}

TEST_F(IoTest, NonHdf5FileIsAnError) {
  const std::string path = file("garbage.hdf5");
  {
    std::ofstream out(path, std::ios::binary);
    for (int i = 0; i < 4096; ++i) out.put(static_cast<char>((i * 7919) & 0xff));
  }
  const std::string msg = error_of([&] { fountain::io::read_initial_conditions(path); });
  EXPECT_TRUE(contains(msg, path)) << msg;
  EXPECT_TRUE(contains(msg, "not an HDF5 file")) << msg;
}

TEST_F(IoTest, TruncatedFileIsAnError) {
  const std::string path = file("ics.hdf5");
  fountain::io::write_initial_conditions(path, make_gas(500), {1, 1, 1}, false);
  fs::resize_file(path, fs::file_size(path) / 2);
  const std::string msg = error_of([&] { fountain::io::read_initial_conditions(path); });
  EXPECT_TRUE(contains(msg, path)) << msg;
}

TEST_F(IoTest, MissingInternalEnergyIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.write_energy = false;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType0/InternalEnergy")) << msg;
  EXPECT_TRUE(contains(msg, "not found")) << msg;
}

TEST_F(IoTest, MissingMassesWithZeroMassTableIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.write_masses = false;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, "/PartType0/Masses")) << msg;
  EXPECT_TRUE(contains(msg, "MassTable")) << msg;
}

TEST_F(IoTest, MassTableIsUsedWhenMassesAreAbsent) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.write_masses = false;
  h.mass_table = {0.25, 0, 0, 0, 0, 0};
  write_by_hand(path, h);
  const auto ic = fountain::io::read_initial_conditions(path);
  ASSERT_EQ(ic.gas.size(), 10u);
  for (double m : ic.gas.mass) EXPECT_EQ(m, 0.25);
  EXPECT_FALSE(ic.has_smoothing_length);
  for (double hh : ic.gas.h) EXPECT_EQ(hh, 0.0);
  EXPECT_EQ(ic.time, 0.0);
  EXPECT_EQ(ic.box_size, (Vec3{4.0, 4.0, 4.0}));
}

TEST_F(IoTest, DatasetLengthDisagreeingWithHeaderIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.header_count = 11;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, "/PartType0/")) << msg;
  EXPECT_TRUE(contains(msg, "10")) << msg;
  EXPECT_TRUE(contains(msg, "11")) << msg;
}

TEST_F(IoTest, ZeroGasParticlesIsAnError) {
  const std::string path = file("ics.hdf5");
  write_by_hand(path, hand_written(0));
  const std::string msg = error_of([&] { fountain::io::read_initial_conditions(path); });
  EXPECT_TRUE(contains(msg, "no gas particles")) << msg;

  const std::string out = file("empty.hdf5");
  error_of([&] { fountain::io::write_initial_conditions(out, GasParticles{}, {1, 1, 1}, true); });
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(IoTest, NanEnergyIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.u[3] = std::numeric_limits<double>::quiet_NaN();
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, "/PartType0/InternalEnergy")) << msg;
  EXPECT_TRUE(contains(msg, "particle ID " + std::to_string(h.ids[3]))) << msg;
}

TEST_F(IoTest, NegativeEnergyNamesTheParticle) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.u[6] = -2.0;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, "/PartType0/InternalEnergy")) << msg;
  EXPECT_TRUE(contains(msg, "particle ID " + std::to_string(h.ids[6]))) << msg;
}

TEST_F(IoTest, NegativeMassNamesTheParticle) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.ids[5] = 17;
  h.mass[5] = -1.0;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType0/Masses: particle ID 17 has mass -1 (must be positive)")) << msg;
}

TEST_F(IoTest, NonFiniteCoordinateNamesTheParticle) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.x[2].y = std::numeric_limits<double>::infinity();
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, "/PartType0/Coordinates: particle ID " + std::to_string(h.ids[2]))) << msg;
}

TEST_F(IoTest, DuplicateIdsAreAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10);
  h.ids[7] = h.ids[2];
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, "/PartType0/ParticleIDs")) << msg;
  EXPECT_TRUE(contains(msg, "particle ID " + std::to_string(h.ids[2]))) << msg;
}

// Ranks that hold their own particles read the gas in shares: laid end to end, the shares are
// the whole read, bit for bit, for any number of ranks (with more ranks than particles, some
// shares are empty), with a MassTable instead of masses, and from GADGET binary files.
TEST_F(IoTest, GasReadInSharesIsTheWholeReadCut) {
  const GasParticles gas = make_gas(37, 1000);
  const std::string path = file("ics.hdf5");
  fountain::io::write_initial_conditions(path, gas, {1.5, 2.5, 3.5}, true, 0.75);
  HandWritten table = hand_written(11);
  table.write_masses = false;
  table.mass_table[0] = 0.25;
  const std::string table_path = file("table.hdf5");
  write_by_hand(table_path, table);
  for (const std::string& p : {path, table_path}) {
    const auto whole = fountain::io::read_initial_conditions(p);
    EXPECT_EQ(whole.gas_first, 0u);
    EXPECT_EQ(whole.gas_total, whole.gas.size());
    for (int ranks : {1, 2, 3, 5, 16, 40}) {
      std::size_t next = 0;
      for (int r = 0; r < ranks; ++r) {
        fountain::io::IcReadOptions options;
        options.share_rank = r;
        options.share_ranks = ranks;
        const auto share = fountain::io::read_initial_conditions(p, options);
        EXPECT_EQ(share.gas_total, whole.gas.size());
        ASSERT_EQ(share.gas_first, next) << p << ", share " << r << " of " << ranks;
        for (std::size_t i = 0; i < share.gas.size(); ++i) {
          const std::size_t w = next + i;
          ASSERT_LT(w, whole.gas.size());
          EXPECT_EQ(share.gas.id[i], whole.gas.id[w]);
          EXPECT_EQ(share.gas.mass[i], whole.gas.mass[w]);
          EXPECT_EQ(share.gas.x[i], whole.gas.x[w]);
          EXPECT_EQ(share.gas.v_full[i], whole.gas.v_full[w]);
          EXPECT_EQ(share.gas.u_full[i], whole.gas.u_full[w]);
          EXPECT_EQ(share.gas.h[i], whole.gas.h[w]);
        }
        next += share.gas.size();
        EXPECT_EQ(share.box_size, whole.box_size);
        EXPECT_EQ(share.time, whole.time);
      }
      EXPECT_EQ(next, whole.gas.size()) << p << " in " << ranks << " shares";
    }
  }
}

// A share's bad particle is named as one rank names it; that no ID repeats is checked by the
// first share alone, which reads every ID however far apart the repeats lie.
TEST_F(IoTest, SharesNameTheirBadParticlesAndTheFirstFindsRepeatedIds) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(30);
  h.mass[25] = -1.0;
  write_by_hand(path, h);
  auto share_error = [&](int r, int ranks) {
    fountain::io::IcReadOptions options;
    options.share_rank = r;
    options.share_ranks = ranks;
    try {
      fountain::io::read_initial_conditions(path, options);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(share_error(0, 3), "");
  EXPECT_EQ(share_error(1, 3), "");
  const std::string bad = share_error(2, 3);
  EXPECT_TRUE(contains(bad, "particle ID " + std::to_string(h.ids[25]) + " has mass -1")) << bad;
  h.mass[25] = 1.0;
  h.ids[28] = h.ids[1];
  write_by_hand(path, h);
  const std::string repeated = share_error(0, 3);
  EXPECT_TRUE(contains(repeated, "particle ID " + std::to_string(h.ids[1]) + " appears more than once")) << repeated;
  EXPECT_EQ(share_error(2, 3), "");
  // A cosmological file is read in shares alike: the first share still finds the repeat, the
  // second reads its rows.
  fountain::io::IcReadOptions cosmological;
  cosmological.cosmological = true;
  cosmological.share_ranks = 2;
  EXPECT_THROW(fountain::io::read_initial_conditions(path, cosmological), InputError);
  cosmological.share_rank = 1;
  const auto second = fountain::io::read_initial_conditions(path, cosmological);
  EXPECT_EQ(second.gas_first, second.gas_total / 2);
  EXPECT_EQ(second.gas.size(), second.gas_total - second.gas_total / 2);
  EXPECT_EQ(second.gas.id[0], h.ids[second.gas_first]);
}

// Single-precision floats, 32-bit IDs and a 3-vector BoxSize, written with the raw C API.
TEST_F(IoTest, ReadsFloat32DataAndUint32Ids) {
  const std::string path = file("float.hdf5");
  const int n = 4;
  {
    hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    hid_t hdr = H5Gcreate2(f, "/Header", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    auto attr = [&](const char* name, hid_t type, hsize_t count, const void* data) {
      hid_t s = H5Screate_simple(1, &count, nullptr);
      hid_t a = H5Acreate2(hdr, name, type, s, H5P_DEFAULT, H5P_DEFAULT);
      H5Awrite(a, type, data);
      H5Aclose(a);
      H5Sclose(s);
    };
    const std::uint32_t counts[6] = {n, 0, 0, 0, 0, 0};
    const double table[6] = {0, 0, 0, 0, 0, 0};
    const double box[3] = {1, 2, 3};
    const float time = 0.5f;
    attr("NumPart_ThisFile", H5T_NATIVE_UINT32, 6, counts);
    attr("NumPart_Total", H5T_NATIVE_UINT32, 6, counts);
    attr("MassTable", H5T_NATIVE_DOUBLE, 6, table);
    attr("BoxSize", H5T_NATIVE_DOUBLE, 3, box);
    attr("Time", H5T_NATIVE_FLOAT, 1, &time);
    H5Gclose(hdr);
    hid_t g = H5Gcreate2(f, "/PartType0", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    auto dset = [&](const char* name, hid_t type, int rank, const hsize_t* dims, const void* data) {
      hid_t s = H5Screate_simple(rank, dims, nullptr);
      hid_t d = H5Dcreate2(g, name, type, s, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
      H5Dclose(d);
      H5Sclose(s);
    };
    const hsize_t d1[1] = {n}, d3[2] = {n, 3};
    const float pos[12] = {0.5f, 1, 1.5f, 0.25f, 0, 0, 0, 0, 0.125f, 0.75f, 0.75f, 0.75f};
    const float vel[12] = {};
    const std::uint32_t ids[4] = {9, 8, 7, 4000000000u};
    const float m[4] = {1, 2, 3, 4};
    const float u[4] = {0.5f, 0.5f, 0.5f, 0.5f};
    const float hs[4] = {0.1f, 0.2f, 0.3f, 0.4f};
    dset("Coordinates", H5T_NATIVE_FLOAT, 2, d3, pos);
    dset("Velocities", H5T_NATIVE_FLOAT, 2, d3, vel);
    dset("ParticleIDs", H5T_NATIVE_UINT32, 1, d1, ids);
    dset("Masses", H5T_NATIVE_FLOAT, 1, d1, m);
    dset("InternalEnergy", H5T_NATIVE_FLOAT, 1, d1, u);
    dset("SmoothingLength", H5T_NATIVE_FLOAT, 1, d1, hs);
    H5Gclose(g);
    H5Fclose(f);
  }
  const auto ic = fountain::io::read_initial_conditions(path);
  ASSERT_EQ(ic.gas.size(), 4u);
  EXPECT_EQ(ic.box_size, (Vec3{1, 2, 3}));
  EXPECT_EQ(ic.time, 0.5);
  EXPECT_EQ(ic.gas.id[3], 4000000000u);
  EXPECT_EQ(ic.gas.x[0], (Vec3{0.5, 1.0, 1.5}));
  EXPECT_EQ(ic.gas.mass[2], 3.0);
  EXPECT_EQ(ic.gas.h[1], static_cast<double>(0.2f));
  EXPECT_TRUE(ic.has_smoothing_length);
}

// ---- Initial conditions with dark matter (/PartType1) ----------------------------------------

TEST_F(IoTest, InitialConditionsRoundTripWithDarkMatter) {
  const GasParticles gas = make_gas(23, 1);
  CollisionlessParticles dm = make_dm(31, 500);
  const std::string path = file("ics_dm.hdf5");
  fountain::io::write_initial_conditions(path, gas, dm, {2.0, 2.0, 2.0}, true, 0.5);

  const auto ic = fountain::io::read_initial_conditions(path);
  EXPECT_EQ(ic.gas.id, gas.id);
  EXPECT_EQ(ic.gas.x, gas.x);
  ASSERT_EQ(ic.dm.size(), dm.size());
  EXPECT_EQ(ic.dm.id, dm.id);
  EXPECT_EQ(ic.dm.mass, dm.mass);
  EXPECT_EQ(ic.dm.x, dm.x);
  EXPECT_EQ(ic.dm.v_full, dm.v_full);
  EXPECT_EQ(ic.dm.a_grav, std::vector<Vec3>(dm.size()));
  EXPECT_EQ(ic.dm.potential, std::vector<double>(dm.size(), 0.0));
  EXPECT_EQ(ic.dm.time_bin, std::vector<fountain::TimeBin>(dm.size(), 0));
  EXPECT_EQ(ic.dm.ti_begin, std::vector<std::int64_t>(dm.size(), 0));

  // All dark matter particles of one mass: the writer puts it in MassTable[1], the reader
  // takes the Masses dataset (or the table when the dataset is absent, below).
  for (double& m : dm.mass) m = 3.0;
  fountain::io::write_initial_conditions(path, gas, dm, {2.0, 2.0, 2.0}, true, 0.5);
  const auto same = fountain::io::read_initial_conditions(path);
  EXPECT_EQ(same.dm.mass, dm.mass);
}

TEST_F(IoTest, FileWithoutDarkMatterGivesNone) {
  const std::string path = file("ics.hdf5");
  fountain::io::write_initial_conditions(path, make_gas(5), {1, 1, 1}, false);
  EXPECT_EQ(fountain::io::read_initial_conditions(path).dm.size(), 0u);
  // An empty /PartType1 group announced as zero particles is no dark matter either.
  fountain::io::write_initial_conditions(path, make_gas(5), CollisionlessParticles{}, {1, 1, 1}, false);
  EXPECT_EQ(fountain::io::read_initial_conditions(path).dm.size(), 0u);
}

// IDs must be unique across gas and dark matter: the writer names the smallest one used twice,
// whether each type's IDs come in order (read where they lie) or not (read from a sorted copy).
TEST_F(IoTest, WriterNamesTheSmallestRepeatedId) {
  const std::string path = file("ics.hdf5");
  GasParticles gas = make_gas(10, 1);              // IDs 1 .. 10
  CollisionlessParticles dm = make_dm(10, 20);     // 20, 23, .., 47
  fountain::io::write_initial_conditions(path, gas, dm, {2, 2, 2}, true);
  auto refusal = [&] { return error_of([&] { fountain::io::write_initial_conditions(path, gas, dm, {2, 2, 2}, true); }); };
  dm.id[7] = 9;
  dm.id[8] = 4;  // unsorted now; 4 and 9 are both the gas's
  EXPECT_TRUE(contains(refusal(), "particle ID 4 is used more than once")) << refusal();
  dm = make_dm(10, 20);
  std::swap(gas.id[0], gas.id[9]);  // gas out of order, 8 twice within it and 23 shared
  gas.id[2] = 23;
  gas.id[5] = 8;
  EXPECT_TRUE(contains(refusal(), "particle ID 8 is used more than once")) << refusal();
}

// The lean stores of a generator (dark matter of both resolutions, written gathered by type a
// piece at a time) and the same particles in a run's stores write the same file.
TEST_F(IoTest, LeanStoresWriteWhatTheRunsStoresWrite) {
  fountain::IcGasParticles gas;
  fountain::IcCollisionlessParticles dm;
  const GasParticles g = make_gas(7, 1);
  const CollisionlessParticles d = make_dm(70000, 100);  // more rows than one piece
  for (std::size_t i = 0; i < g.size(); ++i) gas.push_back(g.id[i], g.mass[i], g.x[i], g.v[i], g.u[i], g.h[i]);
  for (std::size_t i = 0; i < d.size(); ++i)
    dm.push_back(d.id[i], i % 3 == 0 ? fountain::Species::LowResDarkMatter : fountain::Species::DarkMatter,
                 d.mass[i], d.x[i], d.v[i]);
  const fountain::io::CosmologicalIcInfo info{{}, 0.25, {}, {}, {}, {}};
  const std::string lean = file("lean.hdf5"), run = file("run.hdf5");
  fountain::io::write_initial_conditions(lean, gas, dm, 3.0, info);
  fountain::io::write_initial_conditions(run, fountain::to_run_particles(gas), fountain::to_run_particles(dm), 3.0, info);
  const File a(lean, File::Mode::read), b(run, File::Mode::read);
  for (const char* type : {"/PartType0/", "/PartType1/", "/PartType2/"})
    for (const char* name : {"Coordinates", "Velocities", "Masses"}) {
      const std::string dataset = std::string(type) + name;
      EXPECT_EQ(a.read_doubles(dataset), b.read_doubles(dataset)) << dataset;
    }
  EXPECT_EQ(a.read_uint64("/PartType2/ParticleIDs"), b.read_uint64("/PartType2/ParticleIDs"));
  EXPECT_EQ(a.read_doubles("/PartType0/InternalEnergy"), b.read_doubles("/PartType0/InternalEnergy"));
  EXPECT_EQ(a.read_attribute_uint64("/Header", "NumPart_ThisFile"),
            (std::vector<std::uint64_t>{7, 46666, 23334, 0, 0, 0}));
  // The scaled velocities: v' / a^(3/2), here 8 v'.
  EXPECT_EQ(a.read_vec3("/PartType1/Velocities")[0], d.v[1] * 8.0);
}

// Ranks that hold their own particles read shares of the collisionless particles too: the
// rows [N r / R, N (r + 1) / R) of all the collisionless types laid end to end (here a share
// spans the end of type 1 and the start of type 2), together the whole read's bit for bit; an
// ID repeated across the types or with the gas is found by the first share alone.
TEST_F(IoTest, CollisionlessParticlesAreReadInSharesAcrossTheirTypes) {
  const GasParticles g = make_gas(10, 1);
  CollisionlessParticles d = make_dm(13, 100);
  for (std::size_t i = 0; i < d.size(); ++i)
    if (i % 2 == 1) d.species[i] = fountain::Species::LowResDarkMatter, d.mass[i] *= 8.0;
  const fountain::io::CosmologicalIcInfo info{{}, 0.25, {}, {}, {}, {}};
  const std::string path = file("shares.hdf5");
  fountain::io::write_initial_conditions(path, g, d, 3.0, info);
  fountain::io::IcReadOptions options;
  options.cosmological = true;
  const auto whole = fountain::io::read_initial_conditions(path, options);
  ASSERT_EQ(whole.dm.size(), 13u);
  EXPECT_EQ(whole.dm_total, 13u);
  std::vector<std::uint64_t> joined;
  for (int r = 0; r < 3; ++r) {
    options.share_rank = r;
    options.share_ranks = 3;
    const auto share = fountain::io::read_initial_conditions(path, options);
    EXPECT_EQ(share.dm_total, 13u);
    EXPECT_EQ(share.dm_first, 13u * static_cast<std::size_t>(r) / 3) << "share " << r;
    EXPECT_EQ(share.dm.size(), 13u * static_cast<std::size_t>(r + 1) / 3 - 13u * static_cast<std::size_t>(r) / 3);
    for (std::size_t i = 0; i < share.dm.size(); ++i) {
      const std::size_t p = share.dm_first + i;
      EXPECT_EQ(share.dm.species[i], whole.dm.species[p]) << "share " << r << ", row " << i;
      EXPECT_EQ(share.dm.x[i], whole.dm.x[p]);
      EXPECT_EQ(share.dm.mass[i], whole.dm.mass[p]);
    }
    joined.insert(joined.end(), share.dm.id.begin(), share.dm.id.end());
  }
  EXPECT_EQ(joined, whole.dm.id);
  // The same ID for a particle of each type, rows far apart: the first share names it.
  auto share_error = [&](int r) {
    options.share_rank = r;
    try {
      fountain::io::read_initial_conditions(path, options);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // (The writer refuses repeated IDs: the file's last type-2 ID is changed in place.)
  auto set_last_type2_id = [&](std::uint64_t id) {
    hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    hid_t ds = H5Dopen2(f, "/PartType2/ParticleIDs", H5P_DEFAULT);
    std::vector<std::uint64_t> ids(6);
    H5Dread(ds, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, ids.data());
    ids.back() = id;
    H5Dwrite(ds, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, ids.data());
    H5Dclose(ds);
    H5Fclose(f);
  };
  set_last_type2_id(d.id[0]);  // the first row of type 1
  EXPECT_TRUE(contains(share_error(0), "particle ID " + std::to_string(d.id[0]) + " is used by both")) << share_error(0);
  EXPECT_EQ(share_error(2), "");
  set_last_type2_id(g.id[9]);
  EXPECT_TRUE(contains(share_error(0), "is also used by a gas particle")) << share_error(0);
}

TEST_F(IoTest, DarkMatterMassTableIsUsedWhenMassesAreAbsent) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10, 6);
  h.write_dm_masses = false;
  h.mass_table = {0, 0.75, 0, 0, 0, 0};
  write_by_hand(path, h);
  const auto ic = fountain::io::read_initial_conditions(path);
  ASSERT_EQ(ic.dm.size(), 6u);
  EXPECT_EQ(ic.dm.mass, std::vector<double>(6, 0.75));
  EXPECT_EQ(ic.dm.id, h.dm_ids);
  EXPECT_EQ(ic.gas.mass, h.mass);
}

TEST_F(IoTest, DarkMatterMissingMassesWithZeroMassTableIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10, 6);
  h.write_dm_masses = false;
  h.mass_table = {0.5, 0, 0, 0, 0, 0};  // gas masses in the table, none for the dark matter
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType1/Masses: dataset not found and /Header/MassTable[1] is 0")) << msg;
  EXPECT_TRUE(contains(msg, "dark matter masses are missing")) << msg;
}

TEST_F(IoTest, DarkMatterNanCoordinateNamesTheParticle) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10, 6);
  h.dm_x[4].z = std::numeric_limits<double>::quiet_NaN();
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType1/Coordinates: particle ID " + std::to_string(h.dm_ids[4]) +
                                " has non-finite coordinates"))
      << msg;
}

TEST_F(IoTest, DarkMatterNegativeMassNamesTheParticle) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10, 6);
  h.dm_mass[2] = -4.0;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType1/Masses: particle ID " + std::to_string(h.dm_ids[2]) +
                                " has mass -4 (must be positive)"))
      << msg;
}

TEST_F(IoTest, IdSharedByGasAndDarkMatterIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10, 6);
  h.dm_ids[3] = h.ids[8];
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType1/ParticleIDs: particle ID " + std::to_string(h.ids[8]))) << msg;
  EXPECT_TRUE(contains(msg, "unique across gas and dark matter")) << msg;

  // Twice within the dark matter.
  h = hand_written(10, 6);
  h.dm_ids[5] = h.dm_ids[1];
  const std::string twice = read_error(path, h);
  EXPECT_TRUE(contains(twice, "/PartType1/ParticleIDs: particle ID " + std::to_string(h.dm_ids[1]))) << twice;
}

TEST_F(IoTest, DarkMatterCountDisagreeingWithHeaderIsAnError) {
  const std::string path = file("ics.hdf5");
  HandWritten h = hand_written(10, 6);
  h.dm_header_count = 7;
  const std::string msg = read_error(path, h);
  EXPECT_TRUE(contains(msg, path + ": /PartType1/ParticleIDs: has 6 entries but /Header/NumPart_ThisFile[1] "
                                   "announces 7 dark matter particles"))
      << msg;

  h = hand_written(10, 6);
  h.write_dm_group = false;
  const std::string missing = read_error(path, h);
  EXPECT_TRUE(contains(missing, path + ": /PartType1: group not found")) << missing;
}

TEST_F(IoTest, DarkMatterWithoutGasIsAnError) {
  const std::string path = file("ics.hdf5");
  write_by_hand(path, hand_written(0, 8));
  const std::string msg = error_of([&] { fountain::io::read_initial_conditions(path); });
  EXPECT_TRUE(contains(msg, path + ": /Header/NumPart_ThisFile")) << msg;
  EXPECT_TRUE(contains(msg, "no gas particles")) << msg;
  EXPECT_TRUE(contains(msg, "8 dark matter particles")) << msg;
}

// ---- Snapshots ------------------------------------------------------------------------------

TEST_F(IoTest, SnapshotIntoMissingFolderIsAnError) {
  const std::string path = file("no/such/folder/snap_0000.hdf5");
  const std::string msg = error_of([&] { fountain::io::write_snapshot(path, make_gas(5), snapshot_info()); });
  EXPECT_TRUE(contains(msg, "cannot create snapshot " + path)) << msg;
  EXPECT_TRUE(contains(msg, "does not exist")) << msg;
}

TEST_F(IoTest, SnapshotIntoUnwritableFolderIsAnError) {
  // Tests may run as root, who can write anywhere: use a parent that is a regular file.
  const std::string blocker = file("not_a_folder");
  std::ofstream(blocker) << "x";
  const std::string path = blocker + "/snap_0000.hdf5";
  const std::string msg = error_of([&] { fountain::io::write_snapshot(path, make_gas(5), snapshot_info()); });
  EXPECT_TRUE(contains(msg, "cannot create snapshot " + path)) << msg;
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST_F(IoTest, SnapshotContent) {
  const GasParticles gas = make_gas(20, 5);
  const auto info = snapshot_info();
  const std::string path = file("snap_0000.hdf5");
  fountain::io::write_snapshot(path, gas, info);
  EXPECT_FALSE(fs::exists(path + ".tmp"));

  File f(path, File::Mode::read);
  EXPECT_EQ(f.read_vec3("/PartType0/Coordinates"), gas.x);
  EXPECT_EQ(f.read_vec3("/PartType0/Velocities"), gas.v);
  EXPECT_EQ(f.read_doubles("/PartType0/Masses"), gas.mass);
  EXPECT_EQ(f.read_uint64("/PartType0/ParticleIDs"), gas.id);
  EXPECT_EQ(f.read_doubles("/PartType0/Density"), gas.rho);
  EXPECT_EQ(f.read_doubles("/PartType0/NeighbourNumber"), gas.wcount);
  const auto bins = f.read_doubles("/PartType0/TimeBin");
  for (std::size_t i = 0; i < gas.size(); ++i) EXPECT_EQ(bins[i], gas.time_bin[i]);
  const auto p = f.read_doubles("/PartType0/Pressure");
  EXPECT_DOUBLE_EQ(p[3], (info.gamma - 1.0) * gas.rho[3] * gas.u[3]);

  EXPECT_EQ(f.read_attribute_double("/Units", "Unit length in cgs (U_L)"), info.units.length_cgs);
  EXPECT_EQ(f.read_attribute_double("/Units", "Unit mass in cgs (U_M)"), info.units.mass_cgs);
  EXPECT_EQ(f.read_attribute_double("/Units", "Unit time in cgs (U_t)"), info.units.time_cgs());
  EXPECT_EQ(f.read_attribute_double("/Units", "Unit current in cgs (U_I)"), 1.0);
  EXPECT_EQ(f.read_attribute_double("/Units", "Unit temperature in cgs (U_T)"), 1.0);

  EXPECT_EQ(f.read_attribute_string("/Header", "Code"), "Fountain");
  EXPECT_EQ(f.read_attribute_double("/Header", "Time"), 0.125);
  EXPECT_EQ(f.read_attribute_double("/Header", "BoxSize"), 2.0);
  EXPECT_EQ(f.read_attribute_int64("/Header", "Periodic"), std::vector<std::int64_t>{1});
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_Total"), (std::vector<std::uint64_t>{20, 0, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_string("/Code", "Git Revision"), "0123456789ab");
  EXPECT_EQ(f.read_attribute_string("/Code", "Build options"), "Release -O3");
  EXPECT_EQ(f.read_attribute_string("/Parameters", "hydro:gamma"), "1.6666666666666667");
  EXPECT_EQ(f.read_attribute_string("/Parameters", "output:directory"), "out: put");
  EXPECT_EQ(f.read_attribute_string("/Parameters", "run:t_end"), "1");
  EXPECT_EQ(f.read_string("/Parameters/YAML"), info.parameters_yaml);

  EXPECT_EQ(f.read_attribute_doubles("/PartType0/Velocities", "U_L exponent"), std::vector<double>{1.0});
  EXPECT_EQ(f.read_attribute_doubles("/PartType0/Velocities", "U_t exponent"), std::vector<double>{-1.0});
  EXPECT_DOUBLE_EQ(
      f.read_attribute_double("/PartType0/Density", "Conversion factor to CGS (not including cosmological corrections)"),
      info.units.density_cgs());
  EXPECT_FALSE(f.read_attribute_string("/PartType0/Masses", "Description").empty());

  // A snapshot is itself readable as initial conditions (restarting from a snapshot).
  const auto ic = fountain::io::read_initial_conditions(path);
  EXPECT_EQ(ic.gas.x, gas.x);
  EXPECT_EQ(ic.box_size, (Vec3{2, 2, 2}));
}

// Particles drift out of a periodic box between the recuts that fold them back: a snapshot
// stores each one's image in [0, L), including values a hair outside (-2e-25 and
// 1 + 1.9e-12 in a box of 1), and leaves an open box's positions as they are.
TEST_F(IoTest, SnapshotOfAPeriodicBoxHoldsPositionsInsideIt) {
  GasParticles gas = make_gas(4, 5);
  CollisionlessParticles dm = make_dm(2, 1000);
  gas.x[0] = {-2e-25, 0.5, 0.5};
  gas.x[1] = {1.000000000001857, 0.5, 0.5};
  gas.x[2] = {0.25, -0.75, 2.5};
  gas.x[3] = {0.999, 0.0, 0.5};
  dm.x[0] = {3.5, 0.5, -1e-300};
  auto info = snapshot_info();
  info.box_size = {1.0, 2.0, 1.0};
  const std::string path = file("wrapped.hdf5");
  fountain::io::write_snapshot(path, gas, dm, info);
  File f(path, File::Mode::read);
  const auto x = f.read_vec3("/PartType0/Coordinates");
  const auto xd = f.read_vec3("/PartType1/Coordinates");
  for (const auto* xs : {&x, &xd})
    for (const Vec3& p : *xs)
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(p[k], 0.0);
        EXPECT_LT(p[k], info.box_size[k]);
      }
  EXPECT_EQ(x[0], (Vec3{0.0, 0.5, 0.5}));
  EXPECT_NEAR(x[1].x, 1.857e-12, 1e-15);
  EXPECT_EQ(x[2], (Vec3{0.25, 1.25, 0.5}));
  EXPECT_EQ(x[3], gas.x[3]);
  EXPECT_EQ(xd[0], (Vec3{0.5, 0.5, 0.0}));
  info.periodic = false;
  fountain::io::write_snapshot(path, gas, dm, info);
  EXPECT_EQ(File(path, File::Mode::read).read_vec3("/PartType0/Coordinates"), gas.x);
}

TEST_F(IoTest, SnapshotOverwritesAnOldOne) {
  const std::string path = file("snap.hdf5");
  fountain::io::write_snapshot(path, make_gas(3), snapshot_info());
  fountain::io::write_snapshot(path, make_gas(7), snapshot_info());
  File f(path, File::Mode::read);
  EXPECT_EQ(f.read_doubles("/PartType0/Masses").size(), 7u);
}

TEST_F(IoTest, SnapshotWithDarkMatter) {
  GasParticles gas = make_gas(20, 5);
  CollisionlessParticles dm = make_dm(30, 1000);
  for (std::size_t i = 0; i < gas.size(); ++i) {
    gas.a_grav[i] = {0.5 * static_cast<double>(i), -1.0, 2.0};
    gas.potential[i] = -3.0 - static_cast<double>(i);
  }
  for (std::size_t i = 0; i < dm.size(); ++i) {
    dm.a_grav[i] = {-0.25 * static_cast<double>(i), 1.5, 0.0};
    dm.potential[i] = -10.0 + 0.5 * static_cast<double>(i);
  }
  const auto info = snapshot_info();
  const std::string path = file("snap_dm.hdf5");
  fountain::io::write_snapshot(path, gas, dm, info);

  File f(path, File::Mode::read);
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_ThisFile"), (std::vector<std::uint64_t>{20, 30, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_Total"), (std::vector<std::uint64_t>{20, 30, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_Total_HighWord"), std::vector<std::uint64_t>(6, 0));
  EXPECT_EQ(f.read_attribute_doubles("/Header", "MassTable"), std::vector<double>(6, 0.0));
  EXPECT_EQ(f.read_vec3("/PartType1/Coordinates"), dm.x);
  EXPECT_EQ(f.read_vec3("/PartType1/Velocities"), dm.v);
  EXPECT_EQ(f.read_doubles("/PartType1/Masses"), dm.mass);
  EXPECT_EQ(f.read_uint64("/PartType1/ParticleIDs"), dm.id);
  EXPECT_EQ(f.read_doubles("/PartType1/Potential"), dm.potential);
  EXPECT_EQ(f.read_vec3("/PartType1/Acceleration"), dm.a_grav);
  EXPECT_EQ(f.read_doubles("/PartType0/Potential"), gas.potential);
  EXPECT_EQ(f.read_vec3("/PartType0/GravAcceleration"), gas.a_grav);

  // Unit attributes as on the gas datasets.
  EXPECT_EQ(f.read_attribute_doubles("/PartType1/Velocities", "U_t exponent"), std::vector<double>{-1.0});
  EXPECT_EQ(f.read_attribute_doubles("/PartType1/Acceleration", "U_L exponent"), std::vector<double>{1.0});
  EXPECT_EQ(f.read_attribute_doubles("/PartType1/Acceleration", "U_t exponent"), std::vector<double>{-2.0});
  EXPECT_EQ(f.read_attribute_doubles("/PartType1/Potential", "U_L exponent"), std::vector<double>{2.0});
  EXPECT_EQ(f.read_attribute_doubles("/PartType0/GravAcceleration", "U_t exponent"), std::vector<double>{-2.0});
  EXPECT_DOUBLE_EQ(
      f.read_attribute_double("/PartType1/Masses", "Conversion factor to CGS (not including cosmological corrections)"),
      info.units.mass_cgs);
  for (const char* name : {"Coordinates", "Velocities", "Masses", "ParticleIDs", "Potential", "Acceleration"})
    EXPECT_FALSE(f.read_attribute_string(std::string("/PartType1/") + name, "Description").empty()) << name;

  // Read back as initial conditions, dark matter included.
  const auto ic = fountain::io::read_initial_conditions(path);
  EXPECT_EQ(ic.dm.id, dm.id);
  EXPECT_EQ(ic.dm.x, dm.x);
  EXPECT_EQ(ic.dm.mass, dm.mass);

  // Without dark matter: no /PartType1, gravity datasets still there (zeros without gravity).
  const std::string gas_only = file("snap_gas.hdf5");
  fountain::io::write_snapshot(gas_only, make_gas(4), CollisionlessParticles{}, info);
  File g(gas_only, File::Mode::read);
  EXPECT_FALSE(g.exists("/PartType1"));
  EXPECT_EQ(g.read_attribute_uint64("/Header", "NumPart_ThisFile"), (std::vector<std::uint64_t>{4, 0, 0, 0, 0, 0}));
  EXPECT_EQ(g.read_doubles("/PartType0/Potential"), std::vector<double>(4, 0.0));
}

TEST_F(IoTest, SnapshotWrittenInPiecesEqualsTheWholeWrite) {
  // Rank 0 writes a snapshot across MPI ranks from the pieces each rank sends, whose split
  // must not show in the file: every dataset as write_snapshot writes it, bit for bit.
  GasParticles gas = make_gas(23, 5);
  CollisionlessParticles dm = make_dm(17, 1000);
  for (std::size_t i = 0; i < dm.size(); ++i) {
    if (i % 3 == 1) dm.species[i] = fountain::Species::Star;
    if (i % 5 == 2) dm.species[i] = fountain::Species::LowResDarkMatter;
  }
  auto info = snapshot_info();
  info.star_formation = true;
  info.temperature = [](double u) { return 100.0 * u; };
  const std::string whole = file("whole.hdf5"), pieces = file("pieces.hdf5");
  fountain::io::write_snapshot(whole, gas, dm, info);
  {
    const fountain::io::SnapshotCounts counts{gas.size(), dm.count(fountain::Species::DarkMatter),
                                              dm.count(fountain::Species::LowResDarkMatter),
                                              dm.count(fountain::Species::Star)};
    fountain::io::SnapshotWriter writer(pieces, info, counts);
    // Uneven pieces, one empty; the gas from a copy, as a received piece would be.
    GasParticles copy = gas;
    writer.add_gas(copy, 0, 1);
    writer.add_gas(gas, 1, 0);
    writer.add_gas(copy, 1, 14);
    writer.add_gas(gas, 15, 8);
    writer.add_collisionless(dm, 0, 4);
    writer.add_collisionless(dm, 4, 13);
    EXPECT_FALSE(fs::exists(pieces)) << "the file appears only once it is complete";
    writer.close();
  }
  File a(whole, File::Mode::read), b(pieces, File::Mode::read);
  for (const char* group : {"/PartType0", "/PartType1", "/PartType2", "/PartType4"}) {
    ASSERT_TRUE(a.exists(group)) << group;
    hid_t ga = H5Gopen2(a.id(), group, H5P_DEFAULT);
    hsize_t n = 0;
    H5Gget_num_objs(ga, &n);
    ASSERT_GT(n, 5u) << group;
    for (hsize_t k = 0; k < n; ++k) {
      char name[256];
      H5Gget_objname_by_idx(ga, k, name, sizeof name);
      const std::string ds = std::string(group) + "/" + name;
      const std::vector<double> va = a.read_doubles(ds), vb = b.read_doubles(ds);
      ASSERT_EQ(va.size(), vb.size()) << ds;
      EXPECT_EQ(0, std::memcmp(va.data(), vb.data(), va.size() * sizeof(double))) << ds;
      EXPECT_EQ(a.read_attribute_string(ds, "Description"), b.read_attribute_string(ds, "Description")) << ds;
    }
    H5Gclose(ga);
  }
  EXPECT_EQ(a.read_attribute_uint64("/Header", "NumPart_ThisFile"), b.read_attribute_uint64("/Header", "NumPart_ThisFile"));
}

TEST_F(IoTest, SnapshotWriterRefusesMissingOrSurplusParticlesAndLeavesNoFile) {
  const GasParticles gas = make_gas(10);
  const std::string path = file("short.hdf5");
  {
    fountain::io::SnapshotWriter writer(path, snapshot_info(), {10, 0, 0, 0});
    writer.add_gas(gas, 0, 6);
    EXPECT_THROW(writer.add_gas(gas, 6, 5), std::logic_error);  // past the file's 10
    EXPECT_THROW(writer.close(), std::logic_error);            // 4 never came
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

// ---- Restart files --------------------------------------------------------------------------

namespace {

// Bitwise equality of two fields (== would call -0.0 and 0.0 equal).
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// A state whose every field holds distinct values that are not round in binary.
fountain::io::RestartState restart_state(std::size_t n_gas, std::size_t n_dm) {
  fountain::io::RestartState s;
  s.gas = make_gas(n_gas, 1);
  s.dm = make_dm(n_dm, 10000);
  double k = 0.1;
  auto fill = [&](auto& field) {
    for (auto& v : field) {
      k = k * 1.0000001 + 0.7071067811865476;
      using T = std::remove_reference_t<decltype(v)>;
      if constexpr (std::is_same_v<T, Vec3>) {
        v = {k, -k / 3.0, k * 1e-9};
      } else if constexpr (std::is_same_v<T, double>) {
        v = -k / 7.0;
      }
    }
  };
  for (auto* f : {&s.gas.mass, &s.gas.u_full, &s.gas.u, &s.gas.h, &s.gas.rho, &s.gas.rho_msph, &s.gas.h_msph,
                  &s.gas.wcount, &s.gas.wcount_dh, &s.gas.div_v, &s.gas.soundspeed, &s.gas.p_over_rho_a,
                  &s.gas.inv_rho_2ma, &s.gas.balsara, &s.gas.du_dt, &s.gas.potential, &s.dm.mass, &s.dm.potential})
    fill(*f);
  for (auto* f : {&s.gas.x, &s.gas.v_full, &s.gas.v, &s.gas.curl_v, &s.gas.a_hydro, &s.gas.a_grav, &s.dm.x,
                  &s.dm.v_full, &s.dm.v, &s.dm.a_grav})
    fill(*f);
  s.gas.potential[0] = -0.0;  // the sign of zero must survive too
  for (std::size_t i = 0; i < n_gas; ++i) {
    s.gas.ti_begin[i] = static_cast<std::int64_t>(i) << 40;
    s.gas.time_bin[i] = static_cast<fountain::TimeBin>(20 + i % 7);
    s.gas.courant_bin[i] = static_cast<fountain::TimeBin>(30 - i % 5);
    s.gas.limit_bin[i] = i % 3 == 0 ? fountain::kNoBin : static_cast<fountain::TimeBin>(22);
    s.gas.wake_bin[i] = i % 4 == 0 ? static_cast<fountain::TimeBin>(19) : fountain::kNoBin;
  }
  for (std::size_t i = 0; i < n_dm; ++i) {
    s.dm.ti_begin[i] = (static_cast<std::int64_t>(i) << 38) + 5;
    s.dm.time_bin[i] = static_cast<fountain::TimeBin>(18 + i % 9);
  }
  s.ti_current = std::int64_t{1} << 50;
  s.ti_step_begin = (std::int64_t{1} << 50) - (std::int64_t{1} << 44);
  s.steps = 1234;
  s.mesh_step_bin = 47;
  s.mesh_step_begin = std::int64_t{1} << 48;
  s.snapshots_written = 3;
  s.next_output = 4;
  s.parameters_yaml = "run:\n  t_end: 1\n";
  return s;
}

}  // namespace

TEST_F(IoTest, RestartRoundTripWithDarkMatterIsBitwise) {
  const auto s = restart_state(17, 29);
  const std::string path = file("restart.hdf5");
  fountain::io::write_restart(path, s);
  EXPECT_EQ(fountain::io::kRestartFormatVersion, 10);
  const auto r = fountain::io::read_restart(path);

  EXPECT_EQ(r.ti_current, s.ti_current);
  EXPECT_EQ(r.ti_step_begin, s.ti_step_begin);
  EXPECT_EQ(r.mesh_step_bin, s.mesh_step_bin);
  EXPECT_EQ(r.mesh_step_begin, s.mesh_step_begin);
  EXPECT_EQ(r.steps, s.steps);
  EXPECT_EQ(r.snapshots_written, s.snapshots_written);
  EXPECT_EQ(r.next_output, s.next_output);
  EXPECT_EQ(r.parameters_yaml, s.parameters_yaml);

  const auto &g = r.gas, &h = s.gas;
  EXPECT_TRUE(same_bits(g.id, h.id));
  EXPECT_TRUE(same_bits(g.ti_begin, h.ti_begin));
#define FOUNTAIN_SAME(field) EXPECT_TRUE(same_bits(g.field, h.field)) << #field
  FOUNTAIN_SAME(mass); FOUNTAIN_SAME(x); FOUNTAIN_SAME(v_full); FOUNTAIN_SAME(u_full); FOUNTAIN_SAME(v);
  FOUNTAIN_SAME(u); FOUNTAIN_SAME(h); FOUNTAIN_SAME(rho); FOUNTAIN_SAME(rho_msph); FOUNTAIN_SAME(h_msph);
  FOUNTAIN_SAME(wcount); FOUNTAIN_SAME(wcount_dh); FOUNTAIN_SAME(div_v); FOUNTAIN_SAME(curl_v);
  FOUNTAIN_SAME(soundspeed); FOUNTAIN_SAME(p_over_rho_a); FOUNTAIN_SAME(inv_rho_2ma); FOUNTAIN_SAME(balsara);
  FOUNTAIN_SAME(a_hydro); FOUNTAIN_SAME(du_dt); FOUNTAIN_SAME(a_grav); FOUNTAIN_SAME(potential);
  FOUNTAIN_SAME(time_bin); FOUNTAIN_SAME(courant_bin); FOUNTAIN_SAME(limit_bin); FOUNTAIN_SAME(wake_bin);
#undef FOUNTAIN_SAME

  const auto &d = r.dm, &e = s.dm;
  ASSERT_EQ(d.size(), e.size());
#define FOUNTAIN_SAME(field) EXPECT_TRUE(same_bits(d.field, e.field)) << "dm." #field
  FOUNTAIN_SAME(id); FOUNTAIN_SAME(mass); FOUNTAIN_SAME(x); FOUNTAIN_SAME(v_full); FOUNTAIN_SAME(v); FOUNTAIN_SAME(a_grav);
  FOUNTAIN_SAME(potential); FOUNTAIN_SAME(time_bin); FOUNTAIN_SAME(ti_begin);
#undef FOUNTAIN_SAME

  // The dark matter is part of the checksum.
  {
    hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    hid_t ds = H5Dopen2(f, "/DarkMatter/potential", H5P_DEFAULT);
    std::vector<double> p = s.dm.potential;
    p[11] += 1e-12;
    ASSERT_GE(ds, 0);
    EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), 0);
    H5Dclose(ds);
    EXPECT_GE(H5Fclose(f), 0);
  }
  const std::string msg = error_of([&] { fountain::io::read_restart(path); });
  EXPECT_TRUE(contains(msg, path + ": restart file is corrupted")) << msg;

  // A run without dark matter round-trips too.
  fountain::io::write_restart(path, restart_state(5, 0));
  EXPECT_EQ(fountain::io::read_restart(path).dm.size(), 0u);
}

TEST_F(IoTest, RestartWithWrongDarkMatterCountIsRefused) {
  // A file whose dark matter fields disagree with its particle count.
  const std::string path = file("restart.hdf5");
  fountain::io::write_restart(path, restart_state(4, 9));
  {
    hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    hid_t g = H5Gopen2(f, "/Restart", H5P_DEFAULT);
    hid_t a = H5Aopen(g, "CollisionlessParticles", H5P_DEFAULT);
    ASSERT_GE(a, 0);
    const std::int64_t wrong = 10;
    EXPECT_GE(H5Awrite(a, H5T_NATIVE_INT64, &wrong), 0);
    H5Aclose(a);
    H5Gclose(g);
    EXPECT_GE(H5Fclose(f), 0);
  }
  const std::string msg = error_of([&] { fountain::io::read_restart(path); });
  EXPECT_TRUE(contains(msg, path + ": /DarkMatter/id has 9 entries, but the file holds 10 collisionless particles"))
      << msg;

  // A restart file whose dark matter count differs from the initial conditions' is refused
  // before the run starts.
  const std::string ics = file("ics.hdf5");
  fountain::io::write_initial_conditions(ics, make_gas(8), make_dm(6), {2, 2, 2}, false);
  const std::string out = file("out");
  const auto params = fountain::ParameterFile::parse(
      fmt::format("run:\n  t_end: 0.01\ninitial_conditions:\n  file: {}\noutput:\n  directory: {}\n", ics, out),
      file("params.yml"));
  fs::create_directories(out);
  auto state = restart_state(8, 5);
  state.parameters_yaml = fountain::RunConfig::from(params).parameters_yaml;
  fountain::io::write_restart(fountain::restart_path(params), state);
  const std::string run = error_of([&] { fountain::run_simulation(params, {.quiet = true, .threads = 1, .restart = true}); });
  EXPECT_TRUE(contains(run, fountain::restart_path(params) + ": restart file holds 5 dark matter particles, but the "
                                                             "initial conditions " + ics + " have 6"))
      << run;
}

// Writes a snapshot where FOUNTAIN_IO_SNAPSHOT says (and a non-cubic one where
// FOUNTAIN_IO_SNAPSHOT_NONCUBIC says, one with dark matter where FOUNTAIN_IO_SNAPSHOT_DM
// says), for tests/check_snapshot_yt.py.
TEST(IoExternal, WriteSnapshotForExternalCheck) {
  const char* out = std::getenv("FOUNTAIN_IO_SNAPSHOT");
  if (out == nullptr || *out == '\0') GTEST_SKIP() << "FOUNTAIN_IO_SNAPSHOT not set";
  auto info = snapshot_info();
  info.units = fountain::Units{};  // Mpc, Msun, km/s: not yt's GADGET defaults, so units are checked too
  fountain::io::write_snapshot(out, make_gas(1000, 1), info);
  if (const char* odd = std::getenv("FOUNTAIN_IO_SNAPSHOT_NONCUBIC"); odd != nullptr && *odd != '\0') {
    info.box_size = {2.0, 3.0, 4.0};
    fountain::io::write_snapshot(odd, make_gas(500, 1), info);
  }
  if (const char* dm = std::getenv("FOUNTAIN_IO_SNAPSHOT_DM"); dm != nullptr && *dm != '\0') {
    info.box_size = {2.0, 2.0, 2.0};
    fountain::io::write_snapshot(dm, make_gas(400, 1), make_dm(700, 5000), info);
  }
  EXPECT_TRUE(fs::exists(out));
}

namespace {
// Restart state `s` split into two pieces (odd and even indices), written as a set beside `path`;
// with from_rows, each piece as a run writes it, as rows of the whole stores (in falling order).
void write_as_set(const fountain::io::RestartState& s, const std::string& path, long long serial,
                  bool from_rows = false) {
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  for (int r = 0; r < 2; ++r) {
    fountain::io::RestartPiece p;
    std::vector<std::size_t> gi, di;
    for (std::size_t i = static_cast<std::size_t>(r); i < s.gas.size(); i += 2) gi.push_back(i);
    for (std::size_t i = static_cast<std::size_t>(r); i < s.dm.size(); i += 2) di.push_back(i);
    const std::string name = (dir / fountain::io::restart_piece_name(path, serial, r)).string();
    if (from_rows) {
      std::reverse(gi.begin(), gi.end());
      std::reverse(di.begin(), di.end());
      const std::vector<std::uint64_t> gas_index(gi.begin(), gi.end()), dm_index(di.begin(), di.end());
      fountain::io::write_restart_piece(name, fountain::io::RestartPieceRows{s.gas, gi, s.dm, di, gas_index, dm_index});
      continue;
    }
    p.gas = s.gas;
    p.gas.permute(gi);
    p.dm = s.dm;
    p.dm.permute(di);
    p.gas_index.assign(gi.begin(), gi.end());
    p.dm_index.assign(di.begin(), di.end());
    fountain::io::write_restart_piece(name, p);
  }
  fountain::io::RestartState scalars = s;
  scalars.gas = {};
  scalars.dm = {};
  fountain::io::write_restart_master(path, scalars, serial, 2, s.gas.size(), s.dm.size());
}
}  // namespace

TEST_F(IoTest, RestartSetOfPiecesReadsBackAsTheWholeStateBitwise) {
  const auto s = restart_state(17, 29);
  const std::string path = file("restart.hdf5");
  // Pieces written from copies of their particles, or as a run writes them, from rows of its stores.
  for (bool from_rows : {false, true}) {
    write_as_set(s, path, 3, from_rows);
    const auto r = fountain::io::read_restart(path);
    EXPECT_EQ(r.serial, 3);
    EXPECT_EQ(r.steps, s.steps);
    EXPECT_EQ(r.parameters_yaml, s.parameters_yaml);
    ASSERT_EQ(r.gas.size(), s.gas.size());
    EXPECT_TRUE(same_bits(r.gas.id, s.gas.id));
    EXPECT_TRUE(same_bits(r.gas.x, s.gas.x));
    EXPECT_TRUE(same_bits(r.gas.u_full, s.gas.u_full));
    EXPECT_TRUE(same_bits(r.gas.time_bin, s.gas.time_bin));
    EXPECT_TRUE(same_bits(r.gas.potential, s.gas.potential));
    EXPECT_TRUE(same_bits(r.dm.id, s.dm.id));
    EXPECT_TRUE(same_bits(r.dm.v_full, s.dm.v_full));
    EXPECT_TRUE(same_bits(r.dm.ti_begin, s.dm.ti_begin));
  }
  // A newer set replaces it, and the older pieces are then stale and removed.
  write_as_set(s, path, 4);
  fountain::io::remove_stale_restart_pieces(path);
  EXPECT_FALSE(std::filesystem::exists(file(fountain::io::restart_piece_name(path, 3, 0))));
  EXPECT_TRUE(std::filesystem::exists(file(fountain::io::restart_piece_name(path, 4, 1))));
  EXPECT_EQ(fountain::io::read_restart(path).serial, 4);
}

// Ranks that hold shares read some of a set's pieces each (rank r of R: the pieces p with
// p % R == r), with each particle's place: together, every particle once, bit for bit the
// whole read's, the collisionless particles as the gas. A file written whole is read whole.
TEST_F(IoTest, RestartSetReadInSharesGivesEachParticleOnceWithItsPlace) {
  const auto s = restart_state(17, 0);
  const std::string path = file("restart.hdf5");
  write_as_set(s, path, 3);
  const auto whole = fountain::io::read_restart(path);
  for (int ranks : {2, 3}) {
    std::vector<int> seen(s.gas.size(), 0);
    for (int r = 0; r < ranks; ++r) {
      const auto share = fountain::io::read_restart(path, {r, ranks});
      EXPECT_TRUE(share.gas_shared);
      EXPECT_EQ(share.gas_total, s.gas.size());
      EXPECT_EQ(share.steps, s.steps);
      ASSERT_EQ(share.gas_places.size(), share.gas.size());
      EXPECT_EQ(share.gas.size() == 0, r >= 2) << "rank " << r << " of " << ranks;
      for (std::size_t i = 0; i < share.gas.size(); ++i) {
        const std::size_t p = share.gas_places[i];
        ASSERT_LT(p, s.gas.size());
        ++seen[p];
        EXPECT_EQ(share.gas.id[i], whole.gas.id[p]);
        EXPECT_TRUE(same_bits(std::vector<Vec3>{share.gas.x[i]}, std::vector<Vec3>{whole.gas.x[p]}));
        EXPECT_TRUE(same_bits(std::vector<double>{share.gas.potential[i]}, std::vector<double>{whole.gas.potential[p]}));
        EXPECT_EQ(share.gas.ti_begin[i], whole.gas.ti_begin[p]);
      }
    }
    for (int count : seen) EXPECT_EQ(count, 1);
  }
  const std::string with_dm = file("with_dm.hdf5");
  const auto d = restart_state(17, 5);
  write_as_set(d, with_dm, 1);
  const auto whole_dm = fountain::io::read_restart(with_dm);
  std::vector<int> seen(d.dm.size(), 0);
  for (int r = 0; r < 2; ++r) {
    const auto share = fountain::io::read_restart(with_dm, {r, 2});
    EXPECT_EQ(share.dm_total, d.dm.size());
    ASSERT_EQ(share.dm_places.size(), share.dm.size());
    for (std::size_t i = 0; i < share.dm.size(); ++i) {
      const std::size_t p = share.dm_places[i];
      ASSERT_LT(p, d.dm.size());
      ++seen[p];
      EXPECT_EQ(share.dm.id[i], whole_dm.dm.id[p]);
      EXPECT_TRUE(same_bits(std::vector<Vec3>{share.dm.v_full[i]}, std::vector<Vec3>{whole_dm.dm.v_full[p]}));
    }
  }
  for (int count : seen) EXPECT_EQ(count, 1);
}

TEST_F(IoTest, RestartFileWrittenWholeIsReadInSharesOfItsRows) {
  const auto s = restart_state(17, 11);
  const std::string path = file("single.hdf5");
  fountain::io::write_restart(path, s);
  for (int ranks : {2, 3, 5}) {
    for (std::uint64_t run : {1u, 4u, 65536u}) {  // rows per read: every field crosses runs, or none
      std::size_t gas_next = 0, dm_next = 0;
      for (int r = 0; r < ranks; ++r) {
        const auto share = fountain::io::read_restart(path, {r, ranks, run});
        const std::string where = "rank " + std::to_string(r) + " of " + std::to_string(ranks);
        EXPECT_TRUE(share.gas_shared && share.read_as_rows) << where;
        EXPECT_TRUE(share.gas_places.empty() && share.dm_places.empty()) << where;
        EXPECT_EQ(share.gas_total, s.gas.size());
        EXPECT_EQ(share.dm_total, s.dm.size());
        EXPECT_EQ(share.steps, s.steps);
        EXPECT_EQ(share.parameters_yaml, s.parameters_yaml);
        // Rows [N r / R, N (r + 1) / R), as the initial conditions are shared.
        EXPECT_EQ(share.gas_first, s.gas.size() * static_cast<std::size_t>(r) / static_cast<std::size_t>(ranks));
        EXPECT_EQ(share.gas_first, gas_next) << where;
        EXPECT_EQ(share.dm_first, dm_next) << where;
        for (std::size_t i = 0; i < share.gas.size(); ++i) {
          const std::size_t p = share.gas_first + i;
          EXPECT_EQ(share.gas.id[i], s.gas.id[p]);
          EXPECT_TRUE(same_bits(std::vector<Vec3>{share.gas.x[i]}, std::vector<Vec3>{s.gas.x[p]}));
          EXPECT_TRUE(same_bits(std::vector<double>{share.gas.potential[i]}, std::vector<double>{s.gas.potential[p]}));
          EXPECT_EQ(share.gas.ti_begin[i], s.gas.ti_begin[p]);
          EXPECT_EQ(share.gas.wake_bin[i], s.gas.wake_bin[p]);
        }
        for (std::size_t i = 0; i < share.dm.size(); ++i) {
          const std::size_t p = share.dm_first + i;
          EXPECT_EQ(share.dm.id[i], s.dm.id[p]);
          EXPECT_TRUE(same_bits(std::vector<Vec3>{share.dm.v_full[i]}, std::vector<Vec3>{s.dm.v_full[p]}));
          EXPECT_EQ(share.dm.time_bin[i], s.dm.time_bin[p]);
        }
        gas_next = share.gas_first + share.gas.size();
        dm_next = share.dm_first + share.dm.size();
      }
      EXPECT_EQ(gas_next, s.gas.size());
      EXPECT_EQ(dm_next, s.dm.size());
    }
  }
  // Every rank checks the whole file: a change in a row another rank keeps is found.
  {
    hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    hid_t ds = H5Dopen2(f, "/DarkMatter/potential", H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    std::vector<double> p = s.dm.potential;
    p[10] += 1e-12;  // the last rank's row
    EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), 0);
    H5Dclose(ds);
    EXPECT_GE(H5Fclose(f), 0);
  }
  for (std::uint64_t run : {3u, 65536u}) {
    const std::string msg = error_of([&] { fountain::io::read_restart(path, {0, 3, run}); });
    EXPECT_TRUE(contains(msg, path + ": restart file is corrupted")) << msg;
  }
}

TEST_F(IoTest, RestartSetWithAMissingOrCorruptedPieceIsRefusedByName) {
  const auto s = restart_state(17, 29);
  const std::string path = file("restart.hdf5");
  write_as_set(s, path, 1);
  const std::string piece = file(fountain::io::restart_piece_name(path, 1, 1));
  {
    hid_t f = H5Fopen(piece.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    hid_t ds = H5Dopen2(f, "/Gas/u_full", H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    std::vector<double> u(8, 3.25);  // the odd half: 8 of 17
    EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, u.data()), 0);
    H5Dclose(ds);
    H5Fclose(f);
  }
  try {
    (void)fountain::io::read_restart(path);
    ADD_FAILURE() << "a corrupted piece was read";
  } catch (const fountain::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rank1.hdf5: restart piece is corrupted"), std::string::npos) << e.what();
  }
  std::filesystem::remove(piece);
  try {
    (void)fountain::io::read_restart(path);
    ADD_FAILURE() << "a set with a missing piece was read";
  } catch (const fountain::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is missing"), std::string::npos) << e.what();
  }
}
