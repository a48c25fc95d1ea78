// Star formation and multiphase feedback (docs/physics.md sections 5-6) in the engine: the rate
// against its closed form, each eligibility condition, conservation through spawning and
// dissolving, feedback bookkeeping, promotion, and reproducibility across thread counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <tuple>
#include <vector>

#include "TestSetups.hpp"
#include "engine/Engine.hpp"
#include "hydro/Kernel.hpp"
#include "ics/Lattice.hpp"
#include "feedback/FeedbackLaw.hpp"
#include "hydro/MassTransfer.hpp"
#include "star_formation/StarFormationLaw.hpp"
#include "star_formation/StarFormationLoop.hpp"

namespace fountain {
namespace {

// Internal units kpc, Msun, km/s: one time unit is 0.978 Gyr.
Units kpc_units() {
  Units u;
  u.length_cgs = 3.0856775814913673e21;
  return u;
}

constexpr double kSide = 20.0;  // kpc
const Vec3 kCentre{10.0, 10.0, 10.0};
constexpr double kMuFactor = (5.0 / 3.0 - 1.0) * 0.59 * 1.67262192369e-24 / 1.380649e-16;  // T = this u (cgs)

double energy_of(double temperature_k, const Units& units) {
  return temperature_k / kMuFactor / units.specific_energy_cgs();
}

// A cube of cold gas on a BCC lattice, density rho (g cm^-3), temperature T, velocity
// -k (x - centre): converging (div v = -3k) for k > 0.
GasParticles make_cube(int cells, double rho_cgs, double temperature_k, double k, const Units& units) {
  const auto pts = ics::bcc_lattice({0, 0, 0}, {kSide, kSide, kSide}, cells, cells, cells);
  const double rho = rho_cgs / units.density_cgs();
  const double m = rho * kSide * kSide * kSide / static_cast<double>(pts.size());
  GasParticles g;
  g.resize(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    g.id[i] = i + 1;
    g.mass[i] = m;
    g.x[i] = pts[i];
    g.v[i] = g.v_full[i] = (pts[i] - kCentre) * (-k);
    g.u[i] = g.u_full[i] = energy_of(temperature_k, units);
  }
  return g;
}

RunConfig sf_config(int threads = 2) {
  RunConfig c = test::test_config(false, {}, true, threads);
  c.units = kpc_units();
  c.gravity.G = c.units.gravitational_constant();
  c.hydro.neighbours_tolerance = 1e-3;
  c.integration.dt_max = 1.0 / 1024.0;
  c.t_end = 1.0;
  c.star_formation.enabled = true;
  c.feedback.energy_per_solar_mass_erg = 0.0;  // no feedback unless a test sets it
  return c;
}

bool central(const Vec3& x, double radius) {
  const Vec3 d = x - kCentre;
  return dot(d, d) < radius * radius;
}

double gas_mass_near_centre(const Engine& e, const std::vector<std::uint64_t>& ids) {
  double m = 0.0;
  const GasParticles& g = e.gas();
  for (std::size_t i = 0; i < g.size(); ++i)
    if (std::binary_search(ids.begin(), ids.end(), g.id[i])) m += g.mass[i];
  return m;
}

std::vector<std::uint64_t> central_ids(const Engine& e, double radius) {
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < e.gas().size(); ++i)
    if (central(e.gas().x[i], radius)) ids.push_back(e.gas().id[i]);
  std::sort(ids.begin(), ids.end());
  return ids;
}

double total_mass(const Engine& e) { return e.totals().mass; }

// ---- The law itself -----------------------------------------------------------------------

TEST(StarFormationLaw, EachConditionAloneBlocksFormation) {
  star_formation::StarFormationLaw law{0.1, 1.0, 4e4, 1.0};
  const star_formation::GasState ok{-1.0, 2.0, 10.0, 1.0, 1e4};
  EXPECT_EQ(law.check(ok), star_formation::Eligibility::Eligible);
  auto with = [&](auto change) {
    star_formation::GasState s = ok;
    change(s);
    return law.check(s);
  };
  EXPECT_EQ(with([](auto& s) { s.div_v = 0.0; }), star_formation::Eligibility::NotConverging);
  EXPECT_EQ(with([](auto& s) { s.rho = 0.5; }), star_formation::Eligibility::TooSparse);
  EXPECT_EQ(with([](auto& s) { s.sound_speed = 100.0; }), star_formation::Eligibility::PressureSupported);
  EXPECT_EQ(with([](auto& s) { s.temperature = 5e4; }), star_formation::Eligibility::TooHot);
}

TEST(StarFormationLaw, PromotionThresholdIsFiftyTStarUnlessTheHotNeighboursAreHotter) {
  // T* = 4e4 K, 50 T* = 2e6 K.
  EXPECT_DOUBLE_EQ(feedback::promotion_temperature(4e4, 50, 2, 5e5), 2e6);    // mean below 25 T*
  EXPECT_DOUBLE_EQ(feedback::promotion_temperature(4e4, 50, 2, 1.5e6), 2e6);  // 25-50 T*: not 2 <T_hot> = 3e6
  EXPECT_DOUBLE_EQ(feedback::promotion_temperature(4e4, 50, 2, 2e6), 2e6);    // at 50 T*: not higher
  EXPECT_DOUBLE_EQ(feedback::promotion_temperature(4e4, 50, 2, 2.5e6), 5e6);  // above: 2 <T_hot>
  EXPECT_DOUBLE_EQ(feedback::promotion_temperature(4e4, 50, 2, 3e6), 6e6);
  EXPECT_DOUBLE_EQ(feedback::promotion_temperature(4e4, 50, 2, -1.0), 2e6);   // none found
}

TEST(StarFormationLaw, FeedbackSharesAddUpToTheEnergy) {
  const auto s = feedback::split_feedback(3.0, 0.4, 0.25);
  EXPECT_DOUBLE_EQ(s.reservoir, 1.2);
  EXPECT_DOUBLE_EQ(s.hot, 0.75);
  EXPECT_DOUBLE_EQ(s.own + s.reservoir + s.hot, 3.0);
}

// ---- The rate ------------------------------------------------------------------------------

// All central gas is eligible and its density follows its gas mass (rho = y rho_0), so
// dy/dt = -c* y sqrt(4 pi G rho_0 y): y(t) = (1 + a t / 2)^-2 with a = c* sqrt(4 pi G rho_0).
TEST(StarFormationRate, UniformColdGasFollowsTheClosedForm) {
  const Units units = kpc_units();
  RunConfig c = sf_config();
  Engine e(c, make_cube(12, 1e-24, 1e4, 1e-3, units));
  e.initialise();
  const std::vector<std::uint64_t> ids = central_ids(e, 4.0);
  ASSERT_GT(ids.size(), 100u);
  // rho_0 as the code measures it at the start (the mean over the central particles; the
  // first step's conversion has not changed it: density uses the mass the loop saw).
  double rho0 = 0.0, m0 = 0.0;
  for (std::size_t i = 0; i < e.gas().size(); ++i)
    if (std::binary_search(ids.begin(), ids.end(), e.gas().id[i])) {
      rho0 += e.gas().rho[i];
      m0 += e.gas().mass_initial[i];
    }
  rho0 /= static_cast<double>(ids.size());
  const double a = c.star_formation.efficiency * std::sqrt(4.0 * std::numbers::pi * c.gravity.G * rho0);
  const double mass_start = total_mass(e);
  double worst = 0.0;
  int checks = 0;
  // The first step's conversion happened at initialise (t = 0, over the first step).
  while (e.time() < 0.15) {
    e.step();
    // Gas converted so far covers [0, t + dt_next] for each particle: compare at step ends,
    // where every central particle has just converted its next step (one common bin).
    const double t_covered = e.time() + c.integration.dt_max;
    const double y = gas_mass_near_centre(e, ids) / m0;
    const double expected = 1.0 / ((1.0 + 0.5 * a * t_covered) * (1.0 + 0.5 * a * t_covered));
    worst = std::max(worst, std::fabs(y / expected - 1.0));
    ++checks;
  }
  EXPECT_GT(checks, 100);
  std::printf("star formation rate: worst deviation from the closed form %.2e over %d steps\n", worst, checks);
  EXPECT_LT(worst, 0.01) << "gas mass fraction off the closed form by " << worst;
  // The run formed a star particle per central gas particle once y < 0.7.
  EXPECT_GT(e.star_formation_total().stars_spawned, static_cast<long long>(ids.size()) / 2);
  EXPECT_EQ(e.dark_matter().count(Species::Star), static_cast<std::size_t>(e.star_formation_total().stars_spawned));
  EXPECT_NEAR(total_mass(e), mass_start, 1e-12 * mass_start);
}

// Each condition broken alone, everything else as in the rate test: no star forms.
struct BrokenCondition {
  const char* name;
  double k;             // velocity gradient (negative: expanding)
  double temperature;   // K
  double t_star;        // K
  double rho_star_cgs;  // g cm^-3
};

class StarFormationConditions : public ::testing::TestWithParam<BrokenCondition> {};

TEST_P(StarFormationConditions, GasBreakingOneConditionFormsNoStars) {
  const BrokenCondition& b = GetParam();
  const Units units = kpc_units();
  RunConfig c = sf_config();
  c.star_formation.temperature_threshold = b.t_star;
  c.star_formation.density_threshold_cgs = b.rho_star_cgs;
  Engine e(c, make_cube(12, 1e-24, b.temperature, b.k, units));
  e.initialise();
  const std::vector<std::uint64_t> ids = central_ids(e, 4.0);
  for (int s = 0; s < 20; ++s) e.step();
  double hidden = 0.0;
  for (std::size_t i = 0; i < e.gas().size(); ++i)
    if (std::binary_search(ids.begin(), ids.end(), e.gas().id[i])) hidden += e.gas().mass_stars_hidden[i];
  EXPECT_EQ(hidden, 0.0) << b.name;
}

// Controls: the same cube with the condition restored forms stars within these 20 steps
// (the rate test shows it for the baseline; these keep the hot variants honest).
TEST(StarFormationConditions, HotButUnsupportedGasWithAHighThresholdForms) {
  const Units units = kpc_units();
  RunConfig c = sf_config();
  c.star_formation.temperature_threshold = 1e7;
  Engine e(c, make_cube(12, 1e-24, 5e4, 1e-3, units));
  e.initialise();
  for (int s = 0; s < 20; ++s) e.step();
  EXPECT_GT(e.star_formation_total().mass_formed, 0.0);
}

INSTANTIATE_TEST_SUITE_P(
    EachCondition, StarFormationConditions,
    ::testing::Values(BrokenCondition{"expanding (div v > 0)", -1e-3, 1e4, 4e4, 5e-26},
                      BrokenCondition{"below rho*", 1e-3, 1e4, 4e4, 2e-24},
                      // 5e5 K with T* raised to 1e7 K: h / c_s < t_dyn, every other condition holds.
                      BrokenCondition{"pressure supported (h/c_s < t_dyn)", 1e-3, 5e5, 1e7, 5e-26},
                      BrokenCondition{"above T*", 1e-3, 5e4, 4e4, 5e-26}),
    [](const auto& info) { return std::to_string(info.index); });

// ---- Conservation through spawning and dissolving ------------------------------------------

struct MassMomentumEnergy {
  double mass = 0.0;
  Vec3 momentum;
  double energy = 0.0;  // kinetic + thermal (predicted state)
};

MassMomentumEnergy measure(const Engine& e) {
  const Totals t = e.totals();
  return {t.mass, t.momentum, t.kinetic + t.thermal};
}

TEST(StarFormationConservation, SpawningAndDissolvingConserveMassMomentumAndEnergy) {
  const Units units = kpc_units();
  RunConfig c = sf_config();
  Engine e(c, make_cube(8, 1e-24, 1e4, 1e-3, units));
  e.initialise();
  GasParticles& g = e.gas();
  // Set up the thresholds' cases directly: a third of the particles hold hidden stars worth a
  // star particle, a third are down to their dissolving mass, with velocities of all sizes.
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double m0 = g.mass_initial[i];
    g.v[i] = g.v_full[i] = Vec3{std::sin(1.0 * i), std::cos(2.0 * i), std::sin(3.0 * i)} * 30.0;
    if (i % 3 == 0) {
      g.mass_stars_hidden[i] = 0.31 * m0;
      g.mass[i] = 0.69 * m0;
    } else if (i % 3 == 1) {
      g.mass_stars_hidden[i] = 0.2 * m0;
      g.mass[i] = 0.1 * m0;
    }
  }
  const MassMomentumEnergy before = measure(e);
  double momentum_scale = 0.0;
  for (std::size_t i = 0; i < g.size(); ++i) momentum_scale += g.dynamical_mass(i) * norm(g.v[i]);
  const std::size_t n_gas = g.size();
  e.finish_star_formation();
  const MassMomentumEnergy after = measure(e);
  const auto& tally = e.star_formation_last_step();
  EXPECT_GT(tally.stars_spawned, 0);
  EXPECT_GT(tally.gas_dissolved, 0);
  EXPECT_EQ(e.gas().size(), n_gas - static_cast<std::size_t>(tally.gas_dissolved));
  EXPECT_NEAR(after.mass, before.mass, 1e-13 * before.mass);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(after.momentum[k], before.momentum[k], 1e-13 * momentum_scale);
  EXPECT_NEAR(after.energy, before.energy, 1e-12 * before.energy);
  // Spawned stars carry their parent's id, the time and the hidden mass.
  const CollisionlessParticles& s = e.dark_matter();
  ASSERT_EQ(s.count(Species::Star), static_cast<std::size_t>(tally.stars_spawned));
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_GT(s.parent_id[i], 0u);
    EXPECT_GT(s.id[i], n_gas);
    EXPECT_EQ(s.birth_time[i], e.time());
  }
}

// A gas particle part-way through a cooling step (its integrated energy already below the
// predicted one, its rate solved to end the step at the 1e4 K floor) takes in much colder gas
// from a dissolving neighbour: energy, mass and momentum are conserved, and neither the
// particle now nor the end of its step goes below zero (it once did, in the R02 run).
TEST(StarFormationConservation, MixingInColderGasKeepsACoolingParticlePositive) {
  GasParticles g;
  g.resize(1);
  g.mass[0] = 2.0;
  g.u[0] = 586.0;
  g.u_full[0] = 420.0;
  const double remaining = 1.0, floor = 210.0;  // time to the step's end; the floor energy
  g.du_dt_cool[0] = g.du_dt[0] = (floor - g.u[0]) / remaining;
  g.v[0] = g.v_full[0] = Vec3{3.0, 0.0, 0.0};
  star_formation::StarFormationTally tally;
  const double m_in = 6.0, u_in = 20.0;
  const Vec3 v_in{-1.0, 2.0, 0.0};
  const double e_before = g.mass[0] * g.u[0] + 0.5 * g.mass[0] * dot(g.v[0], g.v[0]) + m_in * u_in +
                          0.5 * m_in * dot(v_in, v_in);
  const Vec3 p_before = g.v[0] * g.mass[0] + v_in * m_in;
  tally.kinetic_to_heat += hydro::absorb(g, 0, m_in, 0.0, v_in, u_in, 0.0);
  EXPECT_DOUBLE_EQ(g.mass[0], 8.0);
  const double e_after = g.mass[0] * g.u[0] + 0.5 * g.mass[0] * dot(g.v[0], g.v[0]);
  EXPECT_NEAR(e_after, e_before, 1e-12 * e_before);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(g.v[0][k] * g.mass[0], p_before[k], 1e-12 * norm(p_before));
  EXPECT_GT(g.u[0], 0.0);
  EXPECT_GT(g.u_full[0], 0.0);
  EXPECT_GT(g.u[0] + g.du_dt[0] * remaining, 0.0) << "the rest of the step would cool below zero";
}

// ---- Feedback ------------------------------------------------------------------------------

double thermal_kinetic_reservoir(const Engine& e) {
  const Totals t = e.totals();
  return t.thermal + t.kinetic + t.reservoir;
}

TEST(Feedback, EachChannelGetsItsShareAndTheEnergyBudgetCloses) {
  const Units units = kpc_units();
  RunConfig c = sf_config();
  c.feedback.energy_per_solar_mass_erg = 4e48;
  c.feedback.eps_cold = 0.4;
  c.feedback.eps_hot = 0.35;
  // The cube starts all cold: until its own feedback heats some gas, eps_h finds no hot
  // neighbour and stays with the particle (counted), so both paths are exercised.
  GasParticles gas = make_cube(10, 1e-24, 1e4, 1e-3, units);
  Engine e(c, std::move(gas));
  const double e0 = thermal_kinetic_reservoir(e);
  e.initialise();
  const double e_sn = c.feedback.energy_per_mass(units);
  for (int s = 0; s < 30; ++s) {
    e.step();
    const auto& t = e.star_formation_last_step();
    const double expected = e_sn * t.mass_formed;
    EXPECT_NEAR(t.energy_hot, 0.35 * expected, 1e-12 * expected);
    EXPECT_NEAR(t.energy_reservoir, 0.4 * expected, 1e-12 * expected);
    EXPECT_NEAR(t.energy_own, 0.25 * expected, 1e-12 * expected);
  }
  const auto& total = e.star_formation_total();
  ASSERT_GT(total.mass_formed, 0.0);
  // What the particles hold now = what they held + injected - locked in stars, up to the
  // hydro integration error, which is tiny next to the injected energy.
  const double balance = thermal_kinetic_reservoir(e) - e0 - total.energy_injected() + total.thermal_locked;
  EXPECT_LT(std::fabs(balance), 1e-4 * total.energy_injected()) << balance;
}

TEST(Feedback, WithoutColdAndHotSharesItIsPureThermalFeedback) {
  const Units units = kpc_units();
  RunConfig c = sf_config();
  c.feedback.energy_per_solar_mass_erg = 4e48;
  Engine e(c, make_cube(10, 1e-24, 1e4, 1e-3, units));
  const double e0 = thermal_kinetic_reservoir(e);
  e.initialise();
  for (int s = 0; s < 10; ++s) e.step();
  const auto& total = e.star_formation_total();
  ASSERT_GT(total.mass_formed, 0.0);
  EXPECT_EQ(total.energy_hot, 0.0);
  EXPECT_EQ(total.energy_reservoir, 0.0);
  EXPECT_EQ(total.promotions, 0);
  EXPECT_NEAR(total.energy_own, c.feedback.energy_per_mass(units) * total.mass_formed, 1e-12 * total.energy_own);
  for (double r : e.gas().reservoir) EXPECT_EQ(r, 0.0);
  const double balance = thermal_kinetic_reservoir(e) - e0 - total.energy_own + total.thermal_locked;
  EXPECT_LT(std::fabs(balance), 1e-4 * total.energy_own) << balance;
}

// ---- Promotion ---------------------------------------------------------------------------

// A cold clump (1e-24 g cm^-3, 1e4 K) in hot gas (1e-26 g cm^-3, T_hot) in a periodic box,
// everything at rest but the clump's central particle, which holds hidden stars and a
// reservoir worth `target_k` kelvin. Star formation is on with zero efficiency, so only the
// reservoir acts; h_min > 0 sets a floor of h. Returns the engine after its first (t = 0) step
// and the particle's id.
struct PromotionCase {
  std::unique_ptr<Engine> engine;
  std::uint64_t id = 0;
  double u_before = 0.0, hidden = 0.0, reservoir = 0.0;
  Vec3 momentum_before;
};

PromotionCase promotion_case(double t_hot, double target_k, double h_min = 0.0) {
  const Units units = kpc_units();
  RunConfig c = sf_config();
  c.space.periodic = true;
  c.space.box_size = {kSide, kSide, kSide};
  c.star_formation.efficiency = 0.0;
  c.feedback.energy_per_solar_mass_erg = 4e48;
  c.feedback.eps_cold = 0.5;
  c.hydro.h_min = h_min;
  constexpr double radius = 3.0;
  GasParticles g;
  auto add = [&](const Vec3& x, double m, double u) {
    const std::size_t k = g.size();
    g.resize(k + 1);
    g.id[k] = k + 1;
    g.mass[k] = m;
    g.x[k] = x;
    g.u[k] = g.u_full[k] = u;
  };
  const auto hot = ics::bcc_lattice({0, 0, 0}, {kSide, kSide, kSide}, 12, 12, 12);
  const double m_hot = 1e-26 / units.density_cgs() * kSide * kSide * kSide / static_cast<double>(hot.size());
  for (const Vec3& x : hot)
    if (!central(x, radius)) add(x, m_hot, energy_of(t_hot, units));
  const Vec3 lo = kCentre - Vec3{radius, radius, radius};
  const auto cold = ics::bcc_lattice(lo, {2 * radius, 2 * radius, 2 * radius}, 9, 9, 9);
  const double m_cold = 1e-24 / units.density_cgs() * std::pow(2 * radius, 3) / static_cast<double>(cold.size());
  std::size_t target = 0;
  double best = 1e30;
  for (const Vec3& x : cold)
    if (central(x, radius)) {
      add(x, m_cold, energy_of(1e4, units));
      const double d = norm(x - kCentre);
      if (d < best) best = d, target = g.size() - 1;
    }
  PromotionCase pc;
  pc.id = g.id[target];
  pc.hidden = 0.2 * m_cold;
  g.mass_stars_hidden[target] = pc.hidden;
  g.mass[target] = 0.8 * m_cold;
  g.mass_initial[target] = m_cold;
  g.v[target] = g.v_full[target] = Vec3{10.0, -5.0, 2.0};
  pc.u_before = g.u[target];
  pc.reservoir = g.mass[target] * (energy_of(target_k, units) - pc.u_before);
  g.reservoir[target] = pc.reservoir;
  pc.engine = std::make_unique<Engine>(c, std::move(g));
  pc.momentum_before = pc.engine->totals().momentum;
  pc.engine->initialise();
  return pc;
}

std::size_t index_of(const GasParticles& g, std::uint64_t id) {
  return static_cast<std::size_t>(std::find(g.id.begin(), g.id.end(), id) - g.id.begin());
}

TEST(Promotion, ThresholdIsFiftyTStarUnlessTheHotNeighboursAreHotterThanThat) {
  // 50 T* = 2e6 K. Hot gas at 5e5 K or at 1.5e6 K (between 25 and 50 T*, where twice the mean,
  // 3e6 K, would be higher): 50 T* rules. At 3e6 K, above 50 T*: 2 <T_hot> = 6e6 K rules.
  for (const auto& [t_hot, target, promoted] : std::vector<std::tuple<double, double, bool>>{
           {5e5, 1.8e6, false}, {5e5, 2.2e6, true},      // 50 T* rules
           {1.5e6, 1.8e6, false}, {1.5e6, 2.2e6, true},  // 50 T* rules, not 2 <T_hot>
           {3e6, 5.5e6, false}, {3e6, 6.5e6, true}}) {   // 2 <T_hot> = 6e6 K rules
    const PromotionCase pc = promotion_case(t_hot, target);
    const GasParticles& g = pc.engine->gas();
    const std::size_t i = index_of(g, pc.id);
    EXPECT_EQ(g.promoted[i] != 0, promoted) << "T_hot " << t_hot << ", reservoir worth " << target << " K";
    EXPECT_EQ(g.reservoir[i] == 0.0, promoted);
    EXPECT_EQ(pc.engine->star_formation_total().promotions, promoted ? 1 : 0);
  }
}

// The promoted particle's density is that of itself and its non-cold neighbours within its h,
// which holds N_ngb of them, or more when the floor h_min sets h; its stars went to the cold.
void expect_promoted_into_the_hot_phase(const PromotionCase& pc, double h_min) {
  const Engine& e = *pc.engine;
  const GasParticles& g = e.gas();
  const std::size_t i = index_of(g, pc.id);
  ASSERT_EQ(g.promoted[i], 1);
  EXPECT_EQ(g.promotion_time[i], 0.0);
  EXPECT_NEAR(g.u[i], pc.u_before + pc.reservoir / g.mass[i], 1e-12 * g.u[i]);
  const Units units = kpc_units();
  const double rho_star = 5e-26 / units.density_cgs();
  auto cold = [&](std::size_t j) { return g.rho[j] > 0.1 * rho_star && kMuFactor * g.u[j] * units.specific_energy_cgs() < 8e4; };
  // Its density: itself and its hot neighbours only, h solved again over them.
  const double h_inv = 1.0 / g.h[i];
  double rho = g.mass[i] * kernel::value(0.0, h_inv);
  double w_sum = kernel::value(0.0, h_inv);
  int cold_neighbours = 0;
  double hidden_elsewhere = 0.0;
  Vec3 momentum;
  for (std::size_t j = 0; j < g.size(); ++j) {
    if (j != i) hidden_elsewhere += g.mass_stars_hidden[j];
    momentum += g.v[j] * g.dynamical_mass(j);
    if (j == i) continue;
    const double r = norm(e.space().separation(g.x[j], g.x[i]));
    if (r >= g.h[i]) {
      EXPECT_EQ(g.mass_stars_hidden[j], 0.0) << "stars handed beyond h";
      continue;
    }
    if (cold(j)) {
      cold_neighbours += g.mass_stars_hidden[j] > 0.0 ? 1 : 0;
    } else {
      rho += g.mass[j] * kernel::value(r, h_inv);
      w_sum += kernel::value(r, h_inv);
      EXPECT_EQ(g.mass_stars_hidden[j], 0.0) << "stars handed to a hot neighbour";
    }
  }
  EXPECT_GT(cold_neighbours, 10) << "cold neighbours holding its stars";
  const double hot_neighbours = kernel::volume_factor * std::pow(g.h[i], 3) * w_sum;
  if (h_min > 0.0) {
    EXPECT_EQ(g.h[i], h_min) << "held at the floor";
    EXPECT_GT(hot_neighbours, 32.0 + 1.0) << "more hot neighbours within the floor's kernel";
  } else {
    EXPECT_NEAR(hot_neighbours, 32.0, 1e-6) << "hot neighbour number";
  }
  EXPECT_NEAR(g.rho[i], rho, 1e-12 * rho);
  EXPECT_LT(g.rho[i], 0.1 * 1e-24 / units.density_cgs()) << "density still that of the clump";
  EXPECT_EQ(g.mass_stars_hidden[i], 0.0);
  EXPECT_NEAR(hidden_elsewhere, pc.hidden, 1e-12 * pc.hidden);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(momentum[k], pc.momentum_before[k], 1e-9 * norm(pc.momentum_before));
}

TEST(Promotion, PromotedParticleSeesNoColdNeighboursAndHandsThemItsStars) {
  expect_promoted_into_the_hot_phase(promotion_case(3e6, 6.5e6), 0.0);
}

// GADGET's floor of h binds the promoted particle too: solved over its hot neighbours alone its h
// would fall below the floor every other particle keeps to.
TEST(Promotion, PromotedParticleKeepsToTheFloorOfH) {
  const PromotionCase free_case = promotion_case(3e6, 6.5e6);
  const double h_hot = free_case.engine->gas().h[index_of(free_case.engine->gas(), free_case.id)];
  const double h_min = 1.5 * h_hot;
  expect_promoted_into_the_hot_phase(promotion_case(3e6, 6.5e6, h_min), h_min);
}

// ---- Reproducibility -----------------------------------------------------------------------

TEST(Feedback, OneAndTwoThreadsGiveBitwiseIdenticalResults) {
  const Units units = kpc_units();
  auto run = [&](int threads) {
    RunConfig c = sf_config(threads);
    c.feedback.energy_per_solar_mass_erg = 4e48;
    // Mostly into reservoirs: the gas stays cold and star-forming until promoted, and
    // the promoted particles' hidden stars push their cold neighbours over the spawning mass.
    c.feedback.eps_cold = 0.8;
    c.feedback.eps_hot = 0.2;
    c.star_formation.efficiency = 1.0;
    GasParticles gas = make_cube(8, 1e-24, 1e4, 1e-3, units);
    // One particle in seven hot from the start: eps_h has somewhere to go.
    for (std::size_t i = 0; i < gas.size(); i += 7) gas.u[i] = gas.u_full[i] = energy_of(1e6, units);
    auto e = std::make_unique<Engine>(c, std::move(gas));
    e->set_record_timeline(true);
    e->initialise();
    for (int s = 0; s < 60; ++s) {
      e->step();
      // Spawning recuts the cells after the step: the timeline must still name its own tasks.
      EXPECT_EQ(e->last_records().size(), static_cast<std::size_t>(e->records_graph().size()));
    }
    return e;
  };
  const auto a = run(1), b = run(2);
  const auto& ta = a->star_formation_total();
  std::printf("1 vs 2 threads: %lld stars spawned, %lld gas dissolved, %lld promotions\n", ta.stars_spawned,
              ta.gas_dissolved, ta.promotions);
  EXPECT_GT(ta.mass_formed, 0.0);
  EXPECT_GT(ta.stars_spawned, 0);
  EXPECT_GT(ta.promotions, 0);
  ASSERT_EQ(a->gas().size(), b->gas().size());
  ASSERT_EQ(a->dark_matter().size(), b->dark_matter().size());
  EXPECT_EQ(a->gas().id, b->gas().id);
  EXPECT_EQ(a->gas().mass, b->gas().mass);
  EXPECT_EQ(a->gas().u_full, b->gas().u_full);
  EXPECT_EQ(a->gas().mass_stars_hidden, b->gas().mass_stars_hidden);
  EXPECT_EQ(a->gas().reservoir, b->gas().reservoir);
  EXPECT_EQ(a->gas().promoted, b->gas().promoted);
  for (std::size_t i = 0; i < a->gas().size(); ++i) ASSERT_EQ(a->gas().x[i], b->gas().x[i]);
  EXPECT_EQ(a->dark_matter().mass, b->dark_matter().mass);
  EXPECT_EQ(ta.energy_hot, b->star_formation_total().energy_hot);
}

}  // namespace
}  // namespace fountain
