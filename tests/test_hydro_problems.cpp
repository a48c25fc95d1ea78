// Whole runs of the standard hydro problems against their exact solutions, conservation
// and reproducibility. Resolutions are small so the suite stays fast; the error bounds
// are stated (and justified) in docs/validation.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/HydroReference.hpp"
#include "engine/Engine.hpp"
#include "ics/RotatingSphere.hpp"
#include "ics/TestProblems.hpp"

namespace fountain {
namespace {

RunConfig problem_config(const ics::ProblemIC& ic, double t_end, double dt_max, bool msph, int threads) {
  RunConfig c;
  c.t_begin = 0.0;
  c.t_end = t_end;
  c.threads = threads;
  c.hydro.msph = msph;
  c.integration.dt_min = 1e-10;
  c.integration.dt_max = dt_max;
  c.space.periodic = ic.periodic;
  c.space.box_size = ic.box_size;
  return c;
}

void run_to_end(Engine& e) {
  e.initialise();
  while (!e.finished()) e.step();
  e.drift_all();
}

double sod_l1(const GasParticles& g) {
  static const analysis::SodExact exact(std::string(FOUNTAIN_SOURCE_DIR) + "/data/hydro_tests/sod_exact_gamma5_3_t0.2.txt");
  return analysis::sod_density_l1(g, exact);
}

TEST(SodShock, DensityMatchesExactRiemannSolution) {
  const auto ic = ics::sod_shock(32, 5.0 / 3.0);
  Engine e(problem_config(ic, 0.2, 0.01, false, 2), ic.gas);
  run_to_end(e);
  const double l1 = sod_l1(e.gas());
  RecordProperty("L1_density", std::to_string(l1));
  std::printf("Sod (18432 particles) density L1 per particle in |x-1|<0.5: %.5f\n", l1);
  // Bound: SWIFT reaches 0.0104 at 8x the particles; SPH L1 error falls roughly as
  // resolution^-1 in 1D-equivalent spacing (here 2x coarser), so ~0.025 is expected.
  EXPECT_LT(l1, 0.03);
}

// The reconstructed viscosity keeps the shock: the same bound, and within a tenth of the
// paper's viscosity's error.
TEST(SodShock, ReconstructedViscosityKeepsTheShock) {
  const auto ic = ics::sod_shock(32, 5.0 / 3.0);
  double l1[2];
  for (const bool reconstruction : {false, true}) {
    RunConfig cfg = problem_config(ic, 0.2, 0.01, false, 2);
    cfg.hydro.viscosity_reconstruction = reconstruction;
    Engine e(cfg, ic.gas);
    run_to_end(e);
    l1[reconstruction] = sod_l1(e.gas());
  }
  std::printf("Sod (18432 particles) density L1: paper's viscosity %.5f, reconstructed %.5f\n", l1[0], l1[1]);
  EXPECT_LT(l1[1], 0.03);
  EXPECT_LT(std::fabs(l1[1] - l1[0]), 0.1 * l1[0]);
  EXPECT_NE(l1[1], l1[0]) << "the reconstruction made no difference: is it read?";
}

// The signal-velocity criterion (GADGET-2's, SWIFT's) against the paper's on the same ICs,
// with the constant that gives gas at rest the same step: the same accuracy, in a number of
// steps of its own but of the same order (docs/performance.md, "Courant criteria").
TEST(SodShock, SignalVelocityCriterionKeepsTheAccuracy) {
  const auto ic = ics::sod_shock(32, 5.0 / 3.0);
  auto run = [&](CourantCriterion criterion) {
    RunConfig cfg = problem_config(ic, 0.2, 0.01, false, 2);
    cfg.hydro.courant_criterion = criterion;
    Engine e(cfg, ic.gas);
    run_to_end(e);
    return std::pair{sod_l1(e.gas()), e.steps()};
  };
  const auto [l1_syw, steps_syw] = run(CourantCriterion::Syw);
  const auto [l1_sv, steps_sv] = run(CourantCriterion::SignalVelocity);
  std::printf("Sod: syw L1 %.7f in %lld steps; signal_velocity L1 %.7f in %lld steps\n", l1_syw, steps_syw, l1_sv,
              steps_sv);
  EXPECT_LT(l1_sv, 0.03);
  EXPECT_LT(std::fabs(l1_sv - l1_syw), 0.1 * l1_syw);
  EXPECT_NE(steps_sv, steps_syw) << "the criterion made no difference: is it read?";
  EXPECT_GT(steps_sv, steps_syw / 2);
  EXPECT_LT(steps_sv, 2 * steps_syw);
}

TEST(SodShock, MsphChangesNothingWhenContrastStaysBelowA) {
  const auto ic = ics::sod_shock(24, 5.0 / 3.0);
  auto run = [&](bool msph) {
    Engine e(problem_config(ic, 0.05, 0.01, msph, 2), ic.gas);
    run_to_end(e);
    return e.gas();
  };
  const GasParticles sph = run(false), msph = run(true);
  ASSERT_EQ(sph.size(), msph.size());
  for (std::size_t i = 0; i < sph.size(); ++i) {
    ASSERT_EQ(sph.id[i], msph.id[i]);
    ASSERT_EQ(sph.rho[i], msph.rho[i]) << "particle " << sph.id[i];
    ASSERT_EQ(sph.x[i], msph.x[i]) << "particle " << sph.id[i];
    ASSERT_EQ(sph.u[i], msph.u[i]) << "particle " << sph.id[i];
  }
}

class SedovBlast : public testing::TestWithParam<bool> {};

// With the paper's viscosity and with the reconstructed one (which without its entropy-jump
// weight put the shock 19% short here).
TEST_P(SedovBlast, ShockRadiusAndConservation) {
  const auto ic = ics::sedov_blast(20, 5.0 / 3.0);
  const double t_end = 0.05;
  RunConfig cfg = problem_config(ic, t_end, 5e-4, false, 2);
  cfg.hydro.viscosity_reconstruction = GetParam();
  // Neighbours' steps within 2x: with 4x the energy error at the blast's start is 1.25e-3.
  cfg.hydro.limiter_bins = 1;
  Engine e(cfg, ic.gas);
  e.initialise();
  e.drift_all();
  const Totals start = e.totals();
  while (!e.finished()) e.step();
  e.drift_all();
  const Totals end = e.totals();
  const double r_exact = analysis::sedov_exact_radius(1.0, 1.0, t_end);
  const double r = analysis::sedov_shock_radius(e.gas(), {0.5, 0.5, 0.5}, {1, 1, 1});
  std::printf("Sedov (16000 particles, %s viscosity): shock radius %.4f vs %.4f (%.2f%%); energy drift %.2e; steps %lld\n",
              GetParam() ? "reconstructed" : "paper's", r, r_exact, 100 * (r / r_exact - 1),
              end.energy() / start.energy() - 1, e.steps());
  EXPECT_NEAR(r / r_exact, 1.0, 0.03);
  EXPECT_LT(std::fabs(end.energy() / start.energy() - 1.0), 1e-3);
  // Momentum: zero initially; pairwise-antisymmetric forces keep it at round-off.
  const double p_scale = std::sqrt(2.0 * start.mass * start.energy());
  EXPECT_LT(norm(end.momentum), 1e-12 * p_scale) << "momentum " << norm(end.momentum);
  EXPECT_DOUBLE_EQ(end.mass, start.mass);
}

INSTANTIATE_TEST_SUITE_P(Viscosity, SedovBlast, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& info) { return info.param ? "Reconstructed" : "Papers"; });

TEST(Reproducibility, BitwiseIdenticalOnOneAndTwoThreads) {
  const auto ic = ics::sedov_blast(12, 5.0 / 3.0);
  auto run = [&](int threads) {
    Engine e(problem_config(ic, 0.02, 5e-4, true, threads), ic.gas);
    run_to_end(e);
    return e.gas();
  };
  const GasParticles a = run(1), b = run(2), c = run(2);
  for (const GasParticles* other : {&b, &c}) {
    ASSERT_EQ(a.size(), other->size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.id[i], other->id[i]);
      ASSERT_EQ(a.x[i], other->x[i]) << "particle " << a.id[i];
      ASSERT_EQ(a.v[i], other->v[i]) << "particle " << a.id[i];
      ASSERT_EQ(a.u[i], other->u[i]) << "particle " << a.id[i];
      ASSERT_EQ(a.rho[i], other->rho[i]) << "particle " << a.id[i];
      ASSERT_EQ(a.h[i], other->h[i]) << "particle " << a.id[i];
    }
  }
}

// Evrard (1988) collapse with self-gravity, in its usual units (G = M = R = 1). SWIFT drifts
// 6e-4 in total energy by t = 0.8 at 20k particles; the bound here is 1% of the total energy
// to t = 3, at ~2,200 particles so the test stays fast.
TEST(EvrardCollapse, EnergyAndMomentumConserved) {
  const auto ic = ics::evrard_sphere(8);
  RunConfig c = problem_config(ic, 3.0, 0.01, false, 2);
  c.hydro.neighbours = 50;
  c.integration.dt_min = 1e-9;
  c.gravity.enabled = true;
  c.gravity.G = 1.0;
  c.gravity.softening_gas = 0.02;
  Engine e(c, ic.gas);
  e.initialise();
  e.drift_all();
  const Totals start = e.totals();
  // The discrete sphere's binding energy is close to the continuum's -2/3 G M^2 / R.
  EXPECT_NEAR(start.potential, -2.0 / 3.0, 0.03);
  double max_drift = 0.0, p_max = 0.0, kinetic_peak = 0.0;
  for (double t_check = 0.25; !e.finished(); t_check += 0.25) {
    while (!e.finished() && e.time() < t_check) e.step();
    e.drift_all();
    const Totals now = e.totals();
    max_drift = std::max(max_drift, std::fabs(now.energy() - start.energy()) / std::fabs(start.energy()));
    p_max = std::max(p_max, norm(now.momentum));
    kinetic_peak = std::max(kinetic_peak, now.kinetic);
  }
  std::printf("Evrard (%zu particles) to t = 3: largest |dE/E| %.2e, largest |p| %.2e, peak kinetic %.3f\n",
              ic.gas.size(), max_drift, p_max, kinetic_peak);
  RecordProperty("energy_drift", std::to_string(max_drift));
  EXPECT_LT(max_drift, 1e-2);
  // The collapse really happened: the infall converts a good part of W into kinetic energy.
  EXPECT_GT(kinetic_peak, 0.1);
  // The tree's forces are not exactly antisymmetric (docs/gravity.md): momentum stays at
  // the tree's error level, far below the system's sum of |m v| (~0.5 at the peak).
  EXPECT_LT(p_max, 1e-3);
}

// The paper's rotating sphere in its internal units, to t_end, with gravity (gas softening
// half the dark matter's) on 2 threads.
RunConfig sphere_config(double t_end, double softening_dark_matter) {
  RunConfig c;
  c.t_end = t_end;
  c.threads = 2;
  c.integration.dt_min = 1e-12;
  c.integration.dt_max = 1e-6;
  c.gravity.enabled = true;
  c.gravity.G = Units{}.gravitational_constant();
  c.gravity.softening_dark_matter = softening_dark_matter;
  c.gravity.softening_gas = 0.5 * softening_dark_matter;
  return c;
}

// The paper's sphere with gravity and cooling over its first 30 Myr, before the collapse
// heats anything: the gas only cools, so the thermal energy lost must be the energy the
// cooling radiated, and the total plus the radiated energy must stay constant. (A closing
// half-kick that dropped the cooling rate once left the gas with half the cooling.)
TEST(CoolingSphere, RadiatedEnergyClosesTheBudget) {
  ics::RotatingSphereParams sp;
  sp.particles_per_species = 500;
  ics::RotatingSphereIC ic = ics::rotating_sphere(sp);
  RunConfig c = sphere_config(3.0e-5, 0.002);
  c.cooling.enabled = true;
  c.cooling.table_directory = std::string(FOUNTAIN_SOURCE_DIR) + "/data/cooling/sutherland_dopita_1993";
  Engine e(c, std::move(ic.gas), std::move(ic.dm));
  e.initialise();
  const Totals start = e.totals();
  const double radiated_start = e.radiated_energy();
  while (!e.finished()) e.step();
  e.drift_all();
  const Totals end = e.totals();
  const double radiated = e.radiated_energy() - radiated_start;
  const double lost = start.thermal - end.thermal;
  std::printf("Cooling sphere: thermal %.4e -> %.4e, radiated %.4e, (E + radiated) change %.2e of |E|\n", start.thermal,
              end.thermal, radiated, (end.energy() + radiated - start.energy()) / std::fabs(start.energy()));
  EXPECT_GT(lost, 0.3 * start.thermal);  // the gas does cool a lot in 30 Myr
  EXPECT_NEAR(radiated, lost, 0.05 * lost);
  EXPECT_LT(std::fabs(end.energy() + radiated - start.energy()), 1e-3 * std::fabs(start.energy()));
}

// The paper (section 3.2): without cooling, MSPH is standard SPH, since the rule decouples a
// pair only across a contrast of 10 in density and in energy, which adiabatic flows hardly
// make. The rotating sphere without cooling, past its accretion shock, in both schemes, step
// for step: the runs must stay identical bit for bit while the rule has dropped no pair, and
// may part only once it has.
TEST(NonRadiativeSphere, MsphIsSphUntilTheRuleDecouplesAPair) {
  ics::RotatingSphereParams sp;
  sp.particles_per_species = 500;
  const ics::RotatingSphereIC ic = ics::rotating_sphere(sp);
  auto engine = [&](bool msph) {
    RunConfig c = sphere_config(6.1e-4, 0.004);  // 0.6 Gyr: the accretion shock forms at ~0.4 Gyr
    c.hydro.msph = msph;
    auto e = std::make_unique<Engine>(c, ic.gas, ic.dm);
    e->initialise();
    return e;
  };
  const auto sph = engine(false), msph = engine(true);
  const double u_start = sph->totals().thermal;
  auto identical = [&] {
    const GasParticles &a = sph->gas(), &b = msph->gas();
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a.id[i] != b.id[i] || !(a.x[i] == b.x[i]) || !(a.v_full[i] == b.v_full[i]) || a.u_full[i] != b.u_full[i])
        return false;
    return true;
  };
  long long steps = 0, parted_at = -1;
  double thermal_peak = 0.0;
  while (!sph->finished() && !msph->finished()) {
    sph->step();
    msph->step();
    ++steps;
    thermal_peak = std::max(thermal_peak, sph->totals().thermal);
    if (parted_at < 0 && !identical()) {
      parted_at = steps;
      ASSERT_GT(msph->msph_decoupled(), 0) << "the schemes parted at step " << steps << " with no pair decoupled";
    }
    if (parted_at < 0) {
      ASSERT_EQ(sph->time(), msph->time());
    }
  }
  EXPECT_EQ(sph->msph_decoupled(), 0);
  std::printf("Non-radiative sphere, 500 per species, %lld steps: MSPH decoupled %lld force interactions; the runs %s\n",
              steps, msph->msph_decoupled(),
              parted_at < 0 ? "stayed identical" : ("parted at step " + std::to_string(parted_at)).c_str());
  // Past the accretion shock: the shocked gas has several times its starting heat.
  EXPECT_GT(thermal_peak, 3.0 * u_start);
  if (msph->msph_decoupled() == 0) {
    EXPECT_LT(parted_at, 0);
  }
}

}  // namespace
}  // namespace fountain
