// A comoving run's parameters and initial conditions: output lists, GADGET files of every kind read, and the conversion to code variables.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "app/ComovingStart.hpp"
#include "core/Error.hpp"
#include "engine/RunConfig.hpp"
#include "gravity/GravityParams.hpp"
#include "io/GadgetBinary.hpp"
#include "io/Hdf5File.hpp"
#include "io/InitialConditions.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {
namespace {

const char* kComoving =
    "initial_conditions:\n  file: ics.dat\n  periodic: true\n"
    "cosmology:\n  enabled: true\n  omega_m: 0.3\n  omega_lambda: 0.7\n  omega_b: 0.03\n  hubble_param: 0.6\n"
    "  a_end: 0.05\n"
    "gravity:\n  enabled: true\n  softening_dark_matter: 0.05\n";

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string temp_path(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "fountain_comoving_start";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

TEST(ComovingParameters, OutputTimesAreListsOfScaleFactorsAndRedshifts) {
  const std::string yaml = std::string(kComoving) + "output:\n  scale_factors: [0.03, 0.04]\n  redshifts: 24, 39\n";
  EXPECT_NE(error_of([&] { RunConfig::from(ParameterFile::parse(yaml, "params.yml")); }).find("must decrease"),
            std::string::npos);
  const std::string good = std::string(kComoving) + "output:\n  scale_factors: [0.03, 0.04]\n  redshifts: [39, 24]\n";
  const ParameterFile p = ParameterFile::parse(good, "params.yml");
  EXPECT_EQ(p.reals("output.redshifts"), (std::vector<double>{39, 24}));
  const RunConfig c = RunConfig::from(p);
  EXPECT_EQ(c.output.scale_factors, (std::vector<double>{0.025, 0.03, 0.04}));
  EXPECT_TRUE(c.comoving.enabled);
  EXPECT_EQ(c.comoving.a_begin, 0.0);  // from the file
  EXPECT_EQ(c.t_end, std::log(0.05));
  // The canonical text parses back to the same list (restart files hold it).
  const ParameterFile again = ParameterFile::parse(p.used_as_yaml(), "restart");
  EXPECT_EQ(again.reals("output.scale_factors"), p.reals("output.scale_factors"));
  EXPECT_NE(error_of([&] { ParameterFile::parse(std::string(kComoving) + "output:\n  redshifts: [3, x]\n", "p.yml"); })
                .find("output.redshifts"),
            std::string::npos);
  EXPECT_NE(error_of([&] { ParameterFile::parse(std::string(kComoving) + "output:\n  scale_factors: [0]\n", "p.yml"); })
                .find("out of range"),
            std::string::npos);
}

TEST(ComovingParameters, TimesOfPlainRunsAndKeysOfComovingRunsAreRefusedWhereTheyMeanNothing) {
  // run.t_end is required, but in a comoving run.
  EXPECT_NE(error_of([] { ParameterFile::parse("initial_conditions:\n  file: a.hdf5\n", "p.yml"); })
                .find("required key 'run.t_end'"),
            std::string::npos);
  EXPECT_EQ(error_of([] { ParameterFile::parse(kComoving, "p.yml"); }), "");
  auto config_error = [](const std::string& yaml) {
    return error_of([&] { RunConfig::from(ParameterFile::parse(yaml, "p.yml")); });
  };
  EXPECT_NE(config_error(std::string(kComoving) + "run:\n  t_end: 1\n").find("cosmology.a_begin and cosmology.a_end"),
            std::string::npos);
  EXPECT_NE(config_error(std::string(kComoving) + "output:\n  delta_time: 0.1\n").find("output.scale_factors"),
            std::string::npos);
  EXPECT_NE(config_error("run:\n  t_end: 1\ninitial_conditions:\n  file: a.hdf5\ncosmology:\n  omega_m: 0.25\n")
                .find("key 'cosmology.omega_m' is for comoving runs"),
            std::string::npos);
  std::string baryon_heavy(kComoving);
  baryon_heavy.replace(baryon_heavy.find("omega_b: 0.03"), 13, "omega_b: 0.5");
  EXPECT_NE(config_error(baryon_heavy).find("exceeds cosmology.omega_m"), std::string::npos);
  std::string open_box(kComoving);
  open_box.replace(open_box.find("periodic: true"), 14, "periodic: false");
  EXPECT_NE(config_error(open_box).find("periodic box"), std::string::npos);
}

// The gas's starting temperature: the paper's cosmology decouples at 1 + z = 120.37, and the
// gas is at 56.66 K at z = 49 (with T_CMB = 2.728 K, Eisenstein & Hu's).
TEST(ComovingStart, InitialGasTemperatureFollowsTheCmbThenAdiabaticCooling) {
  const cosmology::CosmologyParams mw{0.3, 0.7, 0.03, 0.6};
  EXPECT_NEAR(cosmology::initial_gas_temperature(mw, 0.02), 56.66, 0.01);
  // Before decoupling the gas has the CMB's temperature.
  EXPECT_NEAR(cosmology::initial_gas_temperature(mw, 1.0 / 500.0), 2.728 * 500.0, 1e-9);
  // Continuous at decoupling.
  const double a_dec = 1.0 / 120.37;
  EXPECT_NEAR(cosmology::initial_gas_temperature(mw, a_dec * (1 - 1e-9)), cosmology::initial_gas_temperature(mw, a_dec * (1 + 1e-9)), 1e-3);
}

// A zoom's GADGET binary file (gas with no internal energy, fine and coarse dark matter in
// kpc/h and 1e10 Msun/h with GADGET's velocities) becomes comoving code variables in Mpc/h,
// Msun/h and v' = a^2 dx/dt.
TEST(ComovingStart, GadgetBinaryZoomBecomesCodeVariables) {
  io::GadgetSnapshot s;
  s.header.time = 0.04;
  s.header.redshift = 24.0;
  s.header.box_size = 20000.0;  // kpc/h
  s.header.omega0 = 0.3;
  s.header.omega_lambda = 0.7;
  s.header.hubble_param = 0.6;
  s.header.mass_table = {0.0, 0.5, 0.0, 0.0, 0.0, 0.0};
  std::uint64_t id = 1;
  auto add = [&](int type, Vec3 x, Vec3 v, double m) {
    io::GadgetParticles& p = s.types[static_cast<std::size_t>(type)];
    p.x.push_back(x);
    p.v.push_back(v);
    p.id.push_back(id++);
    p.mass.push_back(m);
    if (type == 0) p.u.push_back(0.0);
  };
  add(0, {1000, 2000, 3000}, {10, 0, 0}, 0.0625);
  add(1, {1500, 2000, 3000}, {0, 20, 0}, 0.5);
  add(5, {15000, 2000, 3000}, {0, 0, 40}, 4.0);
  add(3, {16000, 2000, 3000}, {0, 0, 5}, 32.0);
  for (int t = 0; t < 6; ++t) s.header.count_total[t] = s.types[static_cast<std::size_t>(t)].x.size();
  s.header.count_this_file = s.header.count_total;
  const std::string path = temp_path("zoom.dat");
  io::write_gadget_binary(path, s, {});

  // Plain runs do not read coarse types or a gas without energy.
  EXPECT_NE(error_of([&] { io::read_initial_conditions(path); }).find("internal energy"), std::string::npos);
  io::InitialConditions ic = io::read_initial_conditions(path, {.cosmological = true});
  EXPECT_EQ(ic.format, "GADGET binary");
  ASSERT_EQ(ic.gas.size(), 1u);
  ASSERT_EQ(ic.dm.size(), 3u);
  EXPECT_FALSE(ic.has_internal_energy);
  EXPECT_EQ(ic.dm.species[0], Species::DarkMatter);
  EXPECT_EQ(ic.dm.species[1], Species::LowResDarkMatter);
  EXPECT_EQ(ic.dm.species[2], Species::LowResDarkMatter);

  const ParameterFile params = ParameterFile::parse(
      "initial_conditions:\n  file: ics.dat\n  periodic: true\n  length_unit_cgs: 3.0856775814913673e21\n"
      "cosmology:\n  enabled: true\n  omega_m: 0.3\n  omega_lambda: 0.7\n  omega_b: 0.03\n  hubble_param: 0.6\n"
      "  a_end: 0.05\ngravity:\n  enabled: true\n  softening_dark_matter: 0.05\n",
      "params.yml");
  RunConfig config = RunConfig::from(params);
  to_comoving_variables(ic, config, params, path);
  EXPECT_EQ(config.comoving.a_begin, 0.04);
  EXPECT_EQ(config.t_begin, std::log(0.04));
  EXPECT_NEAR(ic.box_size.x, 20.0, 1e-12);
  EXPECT_NEAR(ic.gas.x[0].y, 2.0, 1e-12);
  EXPECT_NEAR(ic.gas.mass[0], 0.0625e10, 1e-3);
  // Types in order: 1, then 2, 3 and 5 (the file's type 3 before its type 5).
  EXPECT_NEAR(ic.dm.mass[1], 32e10, 1e-1);
  EXPECT_NEAR(ic.dm.mass[2], 4e10, 1e-2);
  // GADGET velocity w = v_pec / sqrt(a): v' = a v_pec = a^(3/2) w.
  EXPECT_NEAR(ic.gas.v_full[0].x, 10.0 * std::pow(0.04, 1.5), 1e-12);
  EXPECT_NEAR(ic.dm.v[2].z, 40.0 * std::pow(0.04, 1.5), 1e-12);
  // No energy in the file: u' = a^2 u of the decoupled gas's temperature (neutral, mu = 1.1856).
  const double kelvin_per_u = 2.0 / 3.0 * 1.1856 * 1.67262192e-24 / 1.380649e-16 * 1e10;
  EXPECT_NEAR(ic.gas.u[0] / (0.04 * 0.04) * kelvin_per_u, cosmology::initial_gas_temperature(config.comoving.cosmology, 0.04),
              1e-9);

}

TEST(ComovingStart, FileTimeAndCosmologyMustBeTheRuns) {
  io::GadgetSnapshot s;
  s.header.time = 0.02;
  s.header.box_size = 10.0;
  s.header.omega0 = 0.25;
  s.header.omega_lambda = 0.75;
  s.header.hubble_param = 0.7;
  s.types[1].x = {{1, 1, 1}, {2, 2, 2}};
  s.types[1].v = {{0, 0, 0}, {0, 0, 0}};
  s.types[1].id = {1, 2};
  s.types[1].mass = {1, 1};
  s.header.count_total = {0, 2, 0, 0, 0, 0};
  s.header.count_this_file = s.header.count_total;
  const std::string path = temp_path("dm_only.dat");
  io::write_gadget_binary(path, s, {});
  EXPECT_NE(error_of([&] { io::read_initial_conditions(path); }).find("no gas"), std::string::npos);
  auto attempt = [&](const std::string& cosmology_lines) {
    io::InitialConditions ic = io::read_initial_conditions(path, {.cosmological = true});
    const ParameterFile params = ParameterFile::parse(
        "initial_conditions:\n  file: dm_only.dat\n  periodic: true\ncosmology:\n  enabled: true\n" + cosmology_lines +
            "gravity:\n  enabled: true\n  softening_dark_matter: 0.05\n",
        "params.yml");
    RunConfig config = RunConfig::from(params);
    return error_of([&] { to_comoving_variables(ic, config, params, path); });
  };
  EXPECT_EQ(attempt("  omega_m: 0.25\n  omega_lambda: 0.75\n  hubble_param: 0.7\n"), "");
  const std::string time_error = attempt("  omega_m: 0.25\n  omega_lambda: 0.75\n  hubble_param: 0.7\n  a_begin: 0.03\n");
  EXPECT_NE(time_error.find("/Header/Time = 0.02"), std::string::npos) << time_error;
  EXPECT_NE(time_error.find("cosmology.a_begin"), std::string::npos) << time_error;
  const std::string omega_error = attempt("  omega_m: 0.3\n  omega_lambda: 0.75\n  hubble_param: 0.7\n");
  EXPECT_NE(omega_error.find("Omega0 = 0.25"), std::string::npos) << omega_error;
  EXPECT_NE(omega_error.find("cosmology.omega_m"), std::string::npos) << omega_error;
}

// HDF5 initial conditions with low-resolution types 2, 3 and 5 and the file's own /Units;
// IDs must be unique across every type.
TEST(ComovingStart, Hdf5FilesGiveEveryDarkMatterTypeAndTheirUnits) {
  const std::string path = temp_path("types.hdf5");
  {
    io::hdf5::File f(path, io::hdf5::File::Mode::create);
    io::hdf5::write_gadget_header(f, {0, 2, 1, 1, 0, 1}, {5.0}, 0.1);
    f.create_group("/Units");
    f.write_attribute("/Units", "UnitLength_in_cm", 3.0856775814913673e24);
    f.write_attribute("/Units", "UnitMass_in_g", 1.988409870698051e33);
    f.write_attribute("/Units", "UnitVelocity_in_cm_per_s", 1e5);
    std::uint64_t id = 10;
    for (auto [type, n] : {std::pair{1, 2}, {2, 1}, {3, 1}, {5, 1}}) {
      const std::string g = "/PartType" + std::to_string(type);
      f.create_group(g);
      std::vector<Vec3> x, v;
      std::vector<std::uint64_t> ids;
      std::vector<double> m;
      for (int i = 0; i < n; ++i) {
        x.push_back({0.5 * type, 0.5 * i, 1.0});
        v.push_back({0, 0, 0});
        ids.push_back(id++);
        m.push_back(type);
      }
      f.write_dataset(g + "/Coordinates", x);
      f.write_dataset(g + "/Velocities", v);
      f.write_dataset(g + "/ParticleIDs", ids);
      f.write_dataset(g + "/Masses", m);
    }
  }
  const io::InitialConditions ic = io::read_initial_conditions(path, {.cosmological = true});
  ASSERT_EQ(ic.dm.size(), 5u);
  EXPECT_EQ(ic.dm.count(Species::DarkMatter), 2u);
  EXPECT_EQ(ic.dm.count(Species::LowResDarkMatter), 3u);
  EXPECT_EQ(ic.dm.mass[4], 5.0);
  EXPECT_EQ(ic.units.length_cgs, 3.0856775814913673e24);
  EXPECT_EQ(ic.units.mass_cgs, 1.988409870698051e33);
  EXPECT_FALSE(ic.cosmology.present ? ic.cosmology.omega0 != 0.0 : false);
  // Without the cosmological option only the gas and type 1 count: no gas is then an error.
  EXPECT_NE(error_of([&] { io::read_initial_conditions(path); }).find("no gas particles"), std::string::npos);
}

}  // namespace
}  // namespace fountain

namespace fountain {
namespace {

// Softenings of a comoving zoom: a low-resolution particle 8 times the high-resolution mass
// softens over twice the length; every softening is comoving until the dark matter's reaches
// its physical limit, then shrinks as 1/a, keeping the species' ratios.
TEST(ComovingSoftening, LowResolutionParticlesScaleByMassAndAllStopAtThePhysicalLimit) {
  GravityParams g;
  g.softening_dark_matter = 0.05;
  g.softening_gas = 0.025;
  g.low_res_reference_mass = 3.0;
  EXPECT_EQ(g.softening(Species::DarkMatter, 3.0), 0.05);
  EXPECT_NEAR(g.softening(Species::LowResDarkMatter, 24.0), 0.1, 1e-15);
  EXPECT_NEAR(g.softening(Species::LowResDarkMatter, 3.0 * 64.0), 0.2, 1e-15);
  EXPECT_DOUBLE_EQ(g.softening(Species::Star, 1.0), 0.0375);
  EXPECT_EQ(g.softening_factor(0.5), 1.0);  // no limit given
  g.softening_max_physical = 0.01;
  EXPECT_EQ(g.softening_factor(0.1), 1.0);   // a eps' = 0.005 < 0.01: comoving
  EXPECT_DOUBLE_EQ(g.softening_factor(0.2), 1.0);  // at the limit
  EXPECT_NEAR(g.softening_factor(0.5), 0.4, 1e-15);  // physical 0.5 * 0.05 * 0.4 = 0.01
  EXPECT_NEAR(0.5 * g.softening_factor(0.5) * g.softening_dark_matter, 0.01, 1e-15);
}

}  // namespace
}  // namespace fountain
