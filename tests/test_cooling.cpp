// Radiative cooling from the SD93 tables: table values, T(u), and the implicit integration
// against a direct high-accuracy integration of the same tabulated rate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "cooling/RadiativeCooling.hpp"
#include "core/Error.hpp"

namespace fountain {
namespace {

const std::string kTables = std::string(FOUNTAIN_SOURCE_DIR) + "/data/cooling/sutherland_dopita_1993";
constexpr double m_p = 1.67262192e-24;

TEST(CoolingTable, ReproducesTabulatedPeaks) {
  const cooling::CoolingTable solar(kTables, "0");
  EXPECT_NEAR(solar.log_lambda_norm(5.35), -20.96, 1e-9);  // data/cooling/sutherland_dopita_1993/README.md: solar peak
  const cooling::CoolingTable primordial(kTables, "primordial");
  EXPECT_NEAR(primordial.log_lambda_norm(4.20), -21.90, 1e-9);  // H peak
  EXPECT_NEAR(primordial.log_lambda_norm(4.90), -22.23, 1e-9);  // He+ peak
  // Half way between grid points and metallicities: linear in both.
  const cooling::CoolingTable half(kTables, "-0.25");
  const cooling::CoolingTable m05(kTables, "-0.5");
  EXPECT_NEAR(half.log_lambda_norm(5.35), 0.5 * (solar.log_lambda_norm(5.35) + m05.log_lambda_norm(5.35)), 1e-12);
  EXPECT_NEAR(solar.log_lambda_norm(5.375), 0.5 * (solar.log_lambda_norm(5.35) + solar.log_lambda_norm(5.40)), 1e-12);
}

TEST(CoolingTable, BadMetallicityAndMissingFilesAreNamed) {
  EXPECT_THROW(cooling::CoolingTable(kTables, "solar"), InputError);
  EXPECT_THROW(cooling::CoolingTable(kTables, "1.5"), InputError);
  try {
    cooling::CoolingTable("/nonexistent", "primordial");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/mzero.cie"), std::string::npos) << e.what();
  }
}

class Cooling : public testing::TestWithParam<std::tuple<const char*, double, double>> {};

TEST(CoolingRate, TemperatureRoundTripAndIonisedMeanMass) {
  const cooling::CoolingTable t(kTables, "primordial");
  const cooling::RadiativeCooling c(t, Units{});
  for (double temp : {1.5e4, 3e4, 1e5, 1e6, 1e7, 1e8}) EXPECT_NEAR(c.temperature(c.energy_at(temp)) / temp, 1.0, 1e-9);
  // Fully ionised primordial gas: mu ~ 0.59 (table composition, X = 0.79 ... 0.76).
  const double u_cgs = c.energy_at(1e7) * Units{}.specific_energy_cgs();
  const double mu = 1.5 * 1.380649e-16 * 1e7 / u_cgs / m_p;
  EXPECT_NEAR(mu, 0.59, 0.02);
}

TEST(CoolingRate, NothingCoolsAtOrBelowTenThousandKelvin) {
  const cooling::CoolingTable t(kTables, "0");
  const cooling::RadiativeCooling c(t, Units{});
  const double rho = 1.0 * m_p / Units{}.density_cgs();
  const double u = c.energy_at(1e4) * 0.8;
  EXPECT_EQ(c.du_dt(rho, u), 0.0);
  EXPECT_EQ(c.implicit_step(rho, u, 0.0, 1e3), u);
  EXPECT_LT(c.du_dt(rho, c.energy_at(2e4)), 0.0);
}

TEST_P(Cooling, IsochoricCoolingFollowsDirectIntegration) {
  const auto [metallicity, n_h, t0] = GetParam();
  const Units units;
  const cooling::CoolingTable table(kTables, metallicity);
  const cooling::RadiativeCooling c(table, units);
  const double rho = n_h * m_p / 0.76 / units.density_cgs();
  const double u0 = c.energy_at(t0);
  const double t_cool = u0 / -c.du_dt(rho, u0);
  const double t_end = 3.0 * t_cool;
  // Cooling runs away once the gas reaches the peak of the cooling curve, so u(t) falls by
  // orders of magnitude in a short time and comparing u at equal times is ill-conditioned.
  // The comparison is instead the time at which the gas cools through each of a ladder of
  // temperatures, which must agree to 1%. Reference: RK4 in steps of 1e-4 of the local
  // cooling time. The implicit (backward Euler, first-order) solver takes steps of 0.005 of
  // the local cooling time and at most 0.01 of the initial one. (Much longer steps stay stable and end at the floor: see below.)
  auto rate = [&](double u) { return c.du_dt(rho, u); };
  auto local_t_cool = [&](double u) {
    const double r = rate(u);
    return r < 0.0 ? u / -r : t_end;
  };
  auto crossing_times = [&](bool implicit) {
    std::vector<double> times;
    std::vector<double> levels;
    for (double temp = 0.85 * t0; temp > 1.1e4; temp *= 0.85) levels.push_back(c.energy_at(temp));
    double t = 0.0, u = u0;
    std::size_t next = 0;
    while (t < t_end && next < levels.size()) {
      // Near 1e4 K the rate collapses within a few per cent of u: there the local u/|du/dt|
      // overstates the time scale, so steps are also capped at 1% of the initial cooling time.
      const double dt = std::min({(implicit ? 0.005 : 1e-4) * local_t_cool(u), (implicit ? 1e-2 : 2e-4) * t_cool, t_end - t});
      double u_new;
      if (implicit) {
        u_new = c.implicit_step(rho, u, 0.0, dt);
      } else {
        const double k1 = rate(u), k2 = rate(u + 0.5 * dt * k1), k3 = rate(u + 0.5 * dt * k2), k4 = rate(u + dt * k3);
        u_new = std::max(u + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4), c.floor_energy());
      }
      while (next < levels.size() && u_new <= levels[next]) {
        times.push_back(t + dt * (u - levels[next]) / (u - u_new));  // linear within the step
        ++next;
      }
      u = u_new;
      t += dt;
    }
    return times;
  };
  const auto ref = crossing_times(false), imp = crossing_times(true);
  ASSERT_GT(ref.size(), 3u);
  ASSERT_EQ(ref.size(), imp.size());
  for (std::size_t k = 0; k < ref.size(); ++k)
    EXPECT_NEAR(imp[k] / ref[k], 1.0, 0.01) << "crossing " << k << " at " << ref[k] / t_cool << " t_cool";
}

INSTANTIATE_TEST_SUITE_P(DensitiesAndTemperatures, Cooling,
                         testing::Values(std::make_tuple("primordial", 1e-3, 1e7), std::make_tuple("primordial", 1e-2, 1e6),
                                         std::make_tuple("primordial", 1.0, 3e4), std::make_tuple("0", 1e-2, 1e6),
                                         std::make_tuple("-1.5", 0.1, 3e5)));

TEST(CoolingRate, StepFarLongerThanCoolingTimeEndsAtTheFloor) {
  const Units units;
  const cooling::CoolingTable table(kTables, "0");
  const cooling::RadiativeCooling c(table, units);
  const double rho = 1.0 * m_p / 0.76 / units.density_cgs();
  const double u0 = c.energy_at(1e6);
  const double t_cool = u0 / -c.du_dt(rho, u0);
  const double u = c.implicit_step(rho, u0, 0.0, 1e4 * t_cool);
  EXPECT_TRUE(std::isfinite(u));
  EXPECT_NEAR(c.temperature(u) / 1e4, 1.0, 0.01);
  EXPECT_GE(u, c.floor_energy());
  // Heating by hydro on top is kept: the result lies between the floor and u_old + dt du_hydro.
  const double u_heated = c.implicit_step(rho, u0, u0 / t_cool, 0.5 * t_cool);
  EXPECT_GT(u_heated, c.floor_energy());
  EXPECT_LT(u_heated, u0 + 0.5 * u0);
}

}  // namespace
}  // namespace fountain
