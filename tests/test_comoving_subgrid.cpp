// Cooling, star formation and feedback in comoving runs: physical thresholds and rates from comoving variables, against independent solutions.
#include <gtest/gtest.h>

#include "TestSetups.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "cooling/CoolingTable.hpp"
#include "cooling/RadiativeCooling.hpp"
#include "cosmology/Background.hpp"
#include "cosmology/IntegrationFactors.hpp"
#include "engine/Engine.hpp"

namespace fountain {
namespace {

using test::critical_density;
using test::lattice_gas;

// The shared comoving configuration at Omega_m 0.3, Omega_Lambda 0.7 and the given h, with a
// 16^3 mesh and a gas softening of 1/20 of an 8^3 lattice's spacing.
RunConfig comoving_config(double box, double hubble_param, double a_begin, double a_end) {
  RunConfig c = test::comoving_config(box, 0.3, 0.7, a_begin, a_end, 16);
  c.comoving.cosmology.hubble_param = hubble_param;
  c.integration.dt_min = 1e-14;
  c.gravity.softening_gas = 0.05 * box / 8.0;
  return c;
}

// COSMOLOGY.md C1.2: in h-scaled units (Mpc/h, Msun/h, km/s) the cgs values carry h; the
// sub-grid thresholds are physical.
TEST(ComovingSubgrid, PhysicalUnitsCarryTheHubbleParameter) {
  for (const double h : {0.6, 0.7, 1.0}) {
    RunConfig c = comoving_config(10.0, h, 0.1, 1.0);
    const Units u = c.physical_units();
    EXPECT_NEAR(u.density_cgs() / (6.767906e-41 * h * h), 1.0, 1e-6);
    EXPECT_NEAR(u.time_cgs() / (3.085678e19 / h), 1.0, 1e-6);
    EXPECT_NEAR(u.specific_energy_cgs(), 1e10, 1e-6);
    // rho* = 5e-26 g cm^-3 is rho'/a^3 > 7.3878e14 h^-2.
    EXPECT_NEAR(c.star_formation.density_threshold(u) * h * h / 7.3878e14, 1.0, 1e-4);
    // e_sn = 4e48 erg per Msun formed.
    c.feedback.energy_per_solar_mass_erg = 4e48;
    EXPECT_NEAR(c.feedback.energy_per_mass(u) / 2.011658e5, 1.0, 1e-6);
    // G has no h in it.
    EXPECT_NEAR(u.gravitational_constant() / 4.300918e-9, 1.0, 1e-5);
  }
  RunConfig plain;
  EXPECT_EQ(plain.physical_units().length_cgs, plain.units.length_cgs);
}

// A uniform gas box at rest in comoving coordinates, cooling on: each particle's physical u
// follows du/dt = -2 H u + Lambda(u, rho'/a^3) (adiabatic expansion and the tables), which
// is integrated here in ln a by classical Runge-Kutta on a fine grid, independently of the
// engine's implicit per-step solve. The box (h = 0.7, a = 0.1 to 0.25, T = 1.5e6 K at start)
// ends at half the adiabatic energy, through the tables' peak near 1e5 K. The engine holds
// a (so rho) fixed over each step: first order in the step, so halving the largest step in
// ln a must halve the error.
struct CoolingRun {
  double worst, spread, t_end, t_reference, t_adiabatic;
  long long steps;
};

CoolingRun cool_uniform_box(double max_dln_a) {
  const double box = 8.0, h = 0.7, a_begin = 0.1, a_end = 0.25, t_begin = 1.5e6;
  RunConfig cfg = comoving_config(box, h, a_begin, a_end);
  cfg.integration.max_dln_a = max_dln_a;
  cfg.cooling.enabled = true;
  cfg.cooling.table_directory = std::string(FOUNTAIN_SOURCE_DIR) + "/data/cooling/sutherland_dopita_1993";
  const cooling::CoolingTable table(cfg.cooling.tables(), cfg.cooling.metallicity);
  const cooling::RadiativeCooling cool(table, cfg.physical_units(), cfg.cooling.hydrogen_fraction);
  const double u_begin = cool.energy_at(t_begin) * a_begin * a_begin;  // u' = a^2 u
  Engine engine(cfg, lattice_gas(8, box, 0.3, u_begin, [](const Vec3&) { return Vec3{}; }));
  engine.initialise();
  const double rho_comoving = engine.gas().rho[0];
  CoolingRun r{};
  while (engine.ti_current() < TimeLine::ticks) {
    engine.step();
    ++r.steps;
  }
  engine.drift_all();

  const cosmology::Background bg(cfg.comoving.cosmology, 100.0);
  auto rate = [&](double ln_a, double u) {  // du / dln a
    const double a = std::exp(ln_a);
    return (-2.0 * u * bg.hubble(a) + cool.du_dt(rho_comoving / (a * a * a), u)) / bg.hubble(a);
  };
  double u = cool.energy_at(t_begin);
  const int n = 20000;
  const double d = std::log(a_end / a_begin) / n;
  for (int k = 0; k < n; ++k) {
    const double x = std::log(a_begin) + k * d;
    const double k1 = rate(x, u), k2 = rate(x + 0.5 * d, u + 0.5 * d * k1), k3 = rate(x + 0.5 * d, u + 0.5 * d * k2),
                 k4 = rate(x + d, u + d * k3);
    u += d / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  const GasParticles& gas = engine.gas();
  for (std::size_t i = 0; i < gas.size(); ++i) {
    r.worst = std::max(r.worst, std::fabs(gas.u[i] / (a_end * a_end) / u - 1.0));
    r.spread = std::max(r.spread, std::fabs(gas.rho[i] / rho_comoving - 1.0));
  }
  r.t_end = cool.temperature(gas.u[0] / (a_end * a_end));
  r.t_reference = cool.temperature(u);
  r.t_adiabatic = t_begin * (a_begin / a_end) * (a_begin / a_end);
  return r;
}

TEST(ComovingSubgrid, UniformBoxCoolsAsExpansionAndTablesSay) {
  const CoolingRun coarse = cool_uniform_box(0.01), fine = cool_uniform_box(0.005);
  for (const CoolingRun& r : {coarse, fine})
    std::printf("uniform box, a = 0.1 -> 0.25 in %lld steps: T = %.4g K (reference %.4g K, adiabatic alone %.4g K), "
                "largest |u/u_ref - 1| = %.2e, rho' spread %.1e\n",
                r.steps, r.t_end, r.t_reference, r.t_adiabatic, r.worst, r.spread);
  // Radiative cooling matters here, and the run stays above the tables' floor.
  EXPECT_LT(coarse.t_reference, 0.6 * coarse.t_adiabatic);
  EXPECT_GT(coarse.t_reference, 5e4);
  EXPECT_LT(coarse.worst, 1e-2);
  EXPECT_LT(fine.worst, 0.6 * coarse.worst);
  EXPECT_LT(coarse.spread, 1e-6);
}

// A factor of the first `fraction` of the first step of a particle of `bin`.
double first_step_factor(const RunConfig& cfg, const cosmology::IntegrationFactors& f, int bin,
                         cosmology::IntegrationFactors::Kind kind, double fraction = 1.0) {
  const double ln_begin = std::log(cfg.comoving.a_begin);
  const double ln_end = ln_begin + fraction * std::ldexp(std::log(cfg.comoving.a_end / cfg.comoving.a_begin), bin - TimeLine::max_bin);
  return f.factor_between_ln(kind, ln_begin, ln_end);
}

// Star formation reads the physical state: a cold, converging lattice at a = 1/4 whose
// physical density rho'/a^3 lies just above rho* forms stars at the rate of that density
// over the step's cosmic time (dM = M (1 - exp(-c* dt / t_dyn))), its own share of the
// supernova energy raises the physical u by e_sn dM / M; with rho* just above rho'/a^3
// (still 60 times above rho') nothing forms. The velocity field converges physically:
// div v = D'/a^2 + 3 H < 0 needs D' < -3 a^2 H, about -84 per time unit here.
TEST(ComovingSubgrid, StarFormationAndItsFeedbackArePhysical) {
  const double box = 0.5, h = 0.7, a_begin = 0.25;
  const double converge = 60.0;  // v' = -converge (x - centre): D' = -180
  const Vec3 centre{0.5 * box, 0.5 * box, 0.5 * box};
  for (const bool above : {true, false}) {
    RunConfig cfg = comoving_config(box, h, a_begin, 0.3);
    cfg.star_formation.enabled = true;
    cfg.feedback.energy_per_solar_mass_erg = 4e48;
    cfg.feedback.eps_cold = cfg.feedback.eps_hot = 0.0;  // all of it the particle's own
    const Units units = cfg.physical_units();
    const cosmology::Background bg(cfg.comoving.cosmology, 100.0);
    const cosmology::IntegrationFactors factors(bg, 5.0 / 3.0, cfg.comoving.a_begin, cfg.comoving.a_end);
    const double t_k = 1e3, u_physical = 1.5 * 1.380649e-16 * t_k / (1.22 * 1.67262192e-24) / 1e10;
    GasParticles g = lattice_gas(8, box, 0.3, u_physical * a_begin * a_begin,
                                 [&](const Vec3& x) { return (x - centre) * (-converge); });
    // Scale the masses so that the physical density is 8 rho* at a = 1/4 (comoving: 8/64 rho*).
    const double rho_star = cfg.star_formation.density_threshold(units);
    for (double& m : g.mass) m *= 8.0 * rho_star * a_begin * a_begin * a_begin / (0.3 * critical_density());
    g.mass_initial = g.mass;
    Engine probe(cfg, g);
    probe.initialise();
    const double rho_physical = probe.gas().rho[0] / (a_begin * a_begin * a_begin);
    cfg.star_formation.density_threshold_cgs = rho_physical * units.density_cgs() * (above ? 0.99 : 1.01);
    Engine engine(cfg, g);
    engine.initialise();
    const GasParticles& gas = engine.gas();
    const double e_sn = cfg.feedback.energy_per_mass(units);
    std::size_t formed = 0, checked = 0;
    double worst_mass = 0.0, worst_energy = 0.0;
    for (std::size_t i = 0; i < gas.size(); ++i) {
      // The lattice's interior converges; the particles next to the box's faces see the jump
      // of the periodic velocity field.
      Vec3 d = gas.x[i] - centre;
      if (std::max({std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)}) > 0.3 * box) continue;
      ++checked;
      if (gas.mass_stars_hidden[i] > 0.0) ++formed;
      const double rho = gas.rho[i] / (a_begin * a_begin * a_begin);
      const double t_dyn = 1.0 / std::sqrt(4.0 * std::numbers::pi * cfg.gravity.G * rho);
      const double m0 = g.mass[0];
      const double dt = first_step_factor(cfg, factors, gas.time_bin[i], cosmology::IntegrationFactors::time);
      const double dm = -m0 * std::expm1(-cfg.star_formation.efficiency * dt / t_dyn);
      if (!above) continue;
      worst_mass = std::max(worst_mass, std::fabs(gas.mass_stars_hidden[i] / dm - 1.0));
      // u_full is also kicked by hydro's rate over the step's first half.
      const double kick = gas.du_dt[i] * first_step_factor(cfg, factors, gas.time_bin[i], cosmology::IntegrationFactors::drift, 0.5);
      const double du = (gas.u_full[i] - kick) / (a_begin * a_begin) - u_physical;
      worst_energy = std::max(worst_energy, std::fabs(du / (e_sn * dm / gas.mass[i]) - 1.0));
    }
    std::printf("rho* %s rho'/a^3: %zu of %zu interior particles formed stars; worst mass %.1e, energy %.1e\n",
                above ? "below" : "above", formed, checked, worst_mass, worst_energy);
    ASSERT_GT(checked, 20u);
    if (above) {
      EXPECT_EQ(formed, checked);
      EXPECT_LT(worst_mass, 1e-10);
      EXPECT_LT(worst_energy, 1e-8);
    } else {
      EXPECT_EQ(formed, 0u);
    }
  }
}

}  // namespace
}  // namespace fountain
