// Parameter files: validation errors name the key and the file; the reference stays in sync.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/Error.hpp"
#include "params/ParameterFile.hpp"
#include "engine/RunConfig.hpp"
#include "params/ParameterSchema.hpp"

namespace fountain {
namespace {

const char* kMinimal = "run:\n  t_end: 0.2\ninitial_conditions:\n  file: ics.hdf5\n";

std::string error_of(const std::string& yaml) {
  try {
    ParameterFile::parse(yaml, "params.yml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Parameters, MinimalFileGetsDefaults) {
  const auto p = ParameterFile::parse(kMinimal, "params.yml");
  EXPECT_DOUBLE_EQ(p.real("run.t_end"), 0.2);
  EXPECT_DOUBLE_EQ(p.real("hydro.sph_alpha"), 1.5);
  EXPECT_DOUBLE_EQ(p.real("hydro.viscosity_alpha"), 1.3);
  EXPECT_TRUE(p.flag("hydro.msph"));
  EXPECT_EQ(p.text("initial_conditions.file"), "ics.hdf5");
  EXPECT_FALSE(p.was_given("hydro.gamma"));
  // What is recorded in snapshots parses back to the same values.
  const auto again = ParameterFile::parse(p.used_as_yaml(), "used");
  EXPECT_EQ(again.values(), p.values());
}

TEST(Parameters, UnknownKeyIsNamed) {
  const auto msg = error_of(std::string(kMinimal) + "hydro:\n  gama: 1.4\n");
  EXPECT_NE(msg.find("hydro.gama"), std::string::npos) << msg;
  EXPECT_NE(msg.find("params.yml:6"), std::string::npos) << msg;
}

TEST(Parameters, WrongTypeIsNamed) {
  const auto msg = error_of(std::string(kMinimal) + "hydro:\n  gamma: fast\n");
  EXPECT_NE(msg.find("hydro.gamma"), std::string::npos) << msg;
  EXPECT_NE(msg.find("fast"), std::string::npos) << msg;
  EXPECT_NE(error_of(std::string(kMinimal) + "hydro:\n  msph: maybe\n").find("hydro.msph"), std::string::npos);
  EXPECT_NE(error_of(std::string(kMinimal) + "run:\n  threads: 1.5\n").find("run"), std::string::npos);
}

TEST(Parameters, OutOfRangeIsNamed) {
  const auto msg = error_of(std::string(kMinimal) + "hydro:\n  courant: -0.1\n");
  EXPECT_NE(msg.find("hydro.courant"), std::string::npos) << msg;
  EXPECT_NE(msg.find("out of range"), std::string::npos) << msg;
  EXPECT_NE(error_of(std::string(kMinimal) + "hydro:\n  gamma: 1\n").find("hydro.gamma"), std::string::npos);
}

TEST(Parameters, MissingRequiredKeyIsNamed) {
  const auto msg = error_of("initial_conditions:\n  file: ics.hdf5\n");
  EXPECT_NE(msg.find("run.t_end"), std::string::npos) << msg;
  EXPECT_NE(msg.find("params.yml"), std::string::npos) << msg;
}

TEST(Parameters, MalformedYamlGivesLine) {
  const auto msg = error_of("run:\n  t_end: [0.2\n");
  EXPECT_NE(msg.find("params.yml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("malformed"), std::string::npos) << msg;
  EXPECT_NE(error_of("just a string").find("mapping"), std::string::npos);
  EXPECT_NE(error_of(std::string(kMinimal) + "hydro: 3\n").find("hydro"), std::string::npos);
}

TEST(Parameters, MissingFileIsNamed) {
  try {
    ParameterFile::load("/nonexistent/params.yml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/params.yml"), std::string::npos);
  }
}

// Checks across keys happen when the run's configuration is read, still before any work.
std::string config_error_of(const std::string& yaml) {
  try {
    RunConfig::from(ParameterFile::parse(yaml, "params.yml"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Parameters, FeedbackSharesAboveOneAreRefused) {
  const auto msg = config_error_of(std::string(kMinimal) + "feedback:\n  eps_cold: 0.6\n  eps_hot: 0.5\n");
  EXPECT_NE(msg.find("feedback.eps_cold"), std::string::npos) << msg;
  EXPECT_NE(msg.find("params.yml"), std::string::npos) << msg;
  EXPECT_EQ(config_error_of(std::string(kMinimal) + "feedback:\n  eps_cold: 0.4\n  eps_hot: 0.4\n"), "");
}

TEST(Parameters, DissolvingBeforeSpawningIsRefused) {
  const auto msg = config_error_of(std::string(kMinimal) +
                                   "star_formation:\n  spawn_fraction: 0.5\n  dissolve_fraction: 0.6\n");
  EXPECT_NE(msg.find("star_formation.dissolve_fraction"), std::string::npos) << msg;
}

// The floor of h is a multiple of the gas's spline softening length, 2.8 times its Plummer-
// equivalent softening (half the dark matter's when unset), as GADGET's MinGasHsmlFractional
// is; without a softening it has nothing to be a multiple of.
TEST(Parameters, SmoothingLengthFloorFollowsTheGasSoftening) {
  const std::string base = std::string(kMinimal) + "hydro:\n  h_min_ratio: 0.5\n";
  const auto from_dm = RunConfig::from(ParameterFile::parse(base + "gravity:\n  softening_dark_matter: 0.002\n", "p"));
  EXPECT_DOUBLE_EQ(from_dm.hydro.h_min, 0.5 * 2.8 * 0.001);
  const auto from_gas = RunConfig::from(
      ParameterFile::parse(base + "gravity:\n  softening_dark_matter: 0.002\n  softening_gas: 0.003\n", "p"));
  EXPECT_DOUBLE_EQ(from_gas.hydro.h_min, 0.5 * 2.8 * 0.003);
  EXPECT_EQ(RunConfig::from(ParameterFile::parse(kMinimal, "p")).hydro.h_min, 0.0);
  const auto msg = config_error_of(base);
  EXPECT_NE(msg.find("hydro.h_min_ratio"), std::string::npos) << msg;
  EXPECT_NE(msg.find("params.yml"), std::string::npos) << msg;
  const auto above_max = config_error_of(std::string(kMinimal) +
                                         "hydro:\n  h_min_ratio: 0.5\n  h_max: 0.001\n"
                                         "gravity:\n  softening_gas: 0.001\n");
  EXPECT_NE(above_max.find("hydro.h_max"), std::string::npos) << above_max;
}

TEST(Parameters, ReferenceDocumentIsUpToDate) {
  std::ifstream in(std::string(FOUNTAIN_SOURCE_DIR) + "/docs/parameters.md");
  ASSERT_TRUE(in) << "docs/parameters.md is missing: run `fountain params > docs/parameters.md`";
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), parameter_reference_markdown())
      << "docs/parameters.md is stale: run `./build/fountain params > docs/parameters.md`";
}

}  // namespace
}  // namespace fountain
