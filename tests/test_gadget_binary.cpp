// GADGET binary initial conditions (formats 1 and 2): files written to the format's layout are read back exactly, and bad files are named.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/Error.hpp"
#include "io/GadgetBinary.hpp"

namespace fountain::io {
namespace {

std::string temp_path(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "fountain_gadget_binary";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// Gas (5, per-particle masses, u), high-resolution dark matter (7, one mass in the table)
// and coarse dark matter as type 5 (3, masses per particle): the three kinds a zoom has.
// Values are multiples of 1/8, exact in float.
GadgetSnapshot three_types() {
  GadgetSnapshot s;
  s.header.time = 0.02;
  s.header.redshift = 49.0;
  s.header.box_size = 26.6;
  s.header.omega0 = 0.3;
  s.header.omega_lambda = 0.7;
  s.header.hubble_param = 0.6;
  s.header.mass_table = {0.0, 0.75, 0.0, 0.0, 0.0, 0.0};
  std::uint64_t id = 4000000000ull;  // above 2^31: IDs are unsigned
  auto fill = [&](int type, int n, double mass) {
    GadgetParticles& p = s.types[static_cast<std::size_t>(type)];
    for (int i = 0; i < n; ++i) {
      p.x.push_back({0.125 * i, 1.5 + 0.25 * type, 26.5 - 0.125 * i});
      p.v.push_back({-2.5 * i, 0.375 * type, 100.0 + i});
      p.id.push_back(id++);
      p.mass.push_back(mass + 0.125 * (type == 1 ? 0 : i));
      if (type == 0) p.u.push_back(20.0 + 0.5 * i);
    }
  };
  fill(0, 5, 0.125);
  fill(1, 7, 0.75);
  fill(5, 3, 6.0);
  for (int t = 0; t < 6; ++t) s.header.count_total[t] = s.types[static_cast<std::size_t>(t)].x.size();
  s.header.count_this_file = s.header.count_total;
  return s;
}

void expect_same(const GadgetSnapshot& a, const GadgetSnapshot& b) {
  EXPECT_EQ(a.header.count_total, b.header.count_total);
  EXPECT_EQ(a.header.mass_table, b.header.mass_table);
  EXPECT_EQ(a.header.time, b.header.time);
  EXPECT_EQ(a.header.box_size, b.header.box_size);
  EXPECT_EQ(a.header.omega0, b.header.omega0);
  EXPECT_EQ(a.header.omega_lambda, b.header.omega_lambda);
  EXPECT_EQ(a.header.hubble_param, b.header.hubble_param);
  for (int t = 0; t < 6; ++t) {
    const GadgetParticles& p = a.types[static_cast<std::size_t>(t)];
    const GadgetParticles& q = b.types[static_cast<std::size_t>(t)];
    EXPECT_EQ(p.x, q.x) << "type " << t;
    EXPECT_EQ(p.v, q.v) << "type " << t;
    EXPECT_EQ(p.id, q.id) << "type " << t;
    EXPECT_EQ(p.mass, q.mass) << "type " << t;
    EXPECT_EQ(p.u, q.u) << "type " << t;
  }
}

TEST(GadgetBinary, EveryLayoutReadsBackExactly) {
  const GadgetSnapshot s = three_types();
  for (const bool swap : {false, true})
    for (const bool dbl : {false, true})
      for (const bool long_ids : {false, true})
        for (const int files : {1, 2})
          for (const int format : {1, 2}) {
            GadgetBinaryLayout layout;
            layout.swap_bytes = swap;
            layout.double_precision = dbl;
            layout.long_ids = long_ids;
            layout.files = files;
            layout.format = format;
            const std::string path = temp_path("ics");
            for (const std::string& f : {path, path + ".0", path + ".1"}) std::filesystem::remove(f);
            GadgetSnapshot written = s;
            if (!long_ids)
              for (auto& p : written.types)
                for (auto& id : p.id) id &= 0xffffffffu;  // what 32-bit IDs can hold
            write_gadget_binary(path, written, layout);
            SCOPED_TRACE(testing::Message() << "swap " << swap << " double " << dbl << " long ids " << long_ids
                                            << " files " << files << " format " << format);
            ASSERT_TRUE(is_gadget_binary(path));
            expect_same(read_gadget_binary(path), written);
          }
}

TEST(GadgetBinary, HeaderFieldsSitAtTheirOffsets) {
  // The layout of the 256-byte header, byte by byte (GADGET-2's io_header).
  const std::string path = temp_path("offsets");
  write_gadget_binary(path, three_types(), GadgetBinaryLayout{});
  std::ifstream in(path, std::ios::binary);
  char bytes[4 + 256];
  in.read(bytes, sizeof bytes);
  auto at_u32 = [&](int offset) {
    std::uint32_t v;
    std::memcpy(&v, bytes + 4 + offset, 4);
    return v;
  };
  auto at_f64 = [&](int offset) {
    double v;
    std::memcpy(&v, bytes + 4 + offset, 8);
    return v;
  };
  std::uint32_t marker;
  std::memcpy(&marker, bytes, 4);
  EXPECT_EQ(marker, 256u);
  EXPECT_EQ(at_u32(0), 5u);         // npart[0]
  EXPECT_EQ(at_u32(20), 3u);        // npart[5]
  EXPECT_EQ(at_f64(32), 0.75);      // massarr[1]
  EXPECT_EQ(at_f64(72), 0.02);      // time
  EXPECT_EQ(at_f64(80), 49.0);      // redshift
  EXPECT_EQ(at_u32(100), 7u);       // npartTotal[1]
  EXPECT_EQ(at_u32(124), 1u);       // num_files
  EXPECT_EQ(at_f64(128), 26.6);     // BoxSize
  EXPECT_EQ(at_f64(136), 0.3);      // Omega0
  EXPECT_EQ(at_f64(144), 0.7);      // OmegaLambda
  EXPECT_EQ(at_f64(152), 0.6);      // HubbleParam
}

TEST(GadgetBinary, BadFilesAreNamedWithTheirBlock) {
  const std::string path = temp_path("bad");
  write_gadget_binary(path, three_types(), GadgetBinaryLayout{});
  const auto size = std::filesystem::file_size(path);
  auto message_of = [&] {
    try {
      read_gadget_binary(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Truncated inside VEL.
  std::filesystem::resize_file(path, 4 + 256 + 4 + 8 + 15 * 12 + 8 + 40);
  EXPECT_NE(message_of().find("block VEL"), std::string::npos) << message_of();
  EXPECT_NE(message_of().find(path), std::string::npos);
  // A record marker corrupted to announce 4 GB: named as truncated, nothing that large allocated.
  write_gadget_binary(path, three_types(), GadgetBinaryLayout{});
  {
    std::fstream io(path, std::ios::binary | std::ios::in | std::ios::out);
    io.seekp(4 + 256 + 4);
    const std::uint32_t huge = 0xfffffff0u;
    io.write(reinterpret_cast<const char*>(&huge), 4);
  }
  EXPECT_NE(message_of().find("block POS is truncated"), std::string::npos) << message_of();
  // Not GADGET at all.
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "this is not a snapshot";
  }
  EXPECT_NE(message_of().find("not a GADGET binary file"), std::string::npos) << message_of();
  EXPECT_FALSE(is_gadget_binary(path));
  // A header that promises more particles than the blocks hold.
  write_gadget_binary(path, three_types(), GadgetBinaryLayout{});
  {
    std::fstream io(path, std::ios::binary | std::ios::in | std::ios::out);
    io.seekp(4);
    const std::uint32_t more = 6;
    io.write(reinterpret_cast<const char*>(&more), 4);
  }
  EXPECT_NE(message_of().find("block POS"), std::string::npos) << message_of();
  EXPECT_GT(size, 0u);
  // A second file missing from a set.
  GadgetBinaryLayout two;
  two.files = 2;
  const std::string set = temp_path("set");
  write_gadget_binary(set, three_types(), two);
  std::filesystem::remove(set + ".1");
  try {
    read_gadget_binary(set);
    ADD_FAILURE() << "a set missing its second file was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(set + ".1"), std::string::npos) << e.what();
  }
}

// A zoom written by MUSIC's gadget2 plug-in (tests/data/music/zoom_gadget2.conf): 16^3 coarse
// cells, a refined patch of 8^3 with gas, the coarse particles as type 5. What the file must
// say, read by Fountain: the header MUSIC wrote from the configuration, one mass per type, the
// gas-to-dark-matter ratio Omega_b / (Omega_m - Omega_b) in the refined patch, every position
// in the box, and the box's whole matter content, Omega_m rho_crit0 L^3.
TEST(GadgetBinary, ReadsInitialConditionsWrittenByMusic) {
  const GadgetSnapshot s = read_gadget_binary(std::string(FOUNTAIN_SOURCE_DIR) + "/tests/data/music/zoom_gadget2.dat");
  const GadgetHeader& h = s.header;
  EXPECT_DOUBLE_EQ(h.time, 1.0 / 50.0);
  EXPECT_DOUBLE_EQ(h.redshift, 49.0);
  EXPECT_DOUBLE_EQ(h.box_size, 26.6);
  EXPECT_DOUBLE_EQ(h.omega0, 0.3);
  EXPECT_DOUBLE_EQ(h.omega_lambda, 0.7);
  EXPECT_DOUBLE_EQ(h.hubble_param, 0.6);
  EXPECT_EQ(s.types[0].x.size(), 640u);
  EXPECT_EQ(s.types[1].x.size(), 640u);
  EXPECT_EQ(s.types[5].x.size(), 4016u);
  EXPECT_NEAR(h.mass_table[0] / h.mass_table[1], 0.03 / 0.27, 1e-6);
  double total = 0.0;
  for (const GadgetParticles& p : s.types) {
    for (const double m : p.mass) total += m;
    for (const Vec3& x : p.x)
      for (int d = 0; d < 3; ++d) {
        EXPECT_GE(x[d], 0.0);
        EXPECT_LT(x[d], 26.6);
      }
  }
  // rho_crit0 = 27.7537 x 1e10 Msun/h per (Mpc/h)^3 (MUSIC's mass unit is 1e10 Msun/h).
  EXPECT_NEAR(total / (0.3 * 27.75366 * 26.6 * 26.6 * 26.6), 1.0, 1e-3);
  ASSERT_EQ(s.types[0].u.size(), 640u);  // one temperature for all gas
  for (const double u : s.types[0].u) EXPECT_EQ(u, s.types[0].u.front());
  EXPECT_GT(s.types[0].u.front(), 0.0);
}

}  // namespace
}  // namespace fountain::io
