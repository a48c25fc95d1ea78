// The task loops (density, ghost, force) against direct O(N^2) sums, MSPH on and off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstring>
#include <random>

#include "BruteForce.hpp"
#include "TestSetups.hpp"
#include "engine/Engine.hpp"
#include "gravity/DirectSummation.hpp"
#include "gravity/EwaldSummation.hpp"

namespace fountain {
namespace {

enum class Setup { UniformPeriodic, ClumpInHotGas, MixedActive, NearBoundaries, OpenBoundaries };

struct Case {
  Setup setup;
  bool msph;
  bool reconstruction = false;  // hydro.viscosity_reconstruction
};

std::string name(const testing::TestParamInfo<Case>& info) {
  const char* s[] = {"UniformPeriodic", "ClumpInHotGas", "MixedActive", "NearBoundaries", "OpenBoundaries"};
  return std::string(s[static_cast<int>(info.param.setup)]) + (info.param.msph ? "_MSPH" : "_SPH") +
         (info.param.reconstruction ? "_Reconstructed" : "");
}

class HydroBruteForce : public testing::TestWithParam<Case> {};

// Relative agreement, with a floor at 1e-5 of the typical magnitude for values near zero.
void expect_close(double loop, double ref, double scale, const char* what, std::size_t id) {
  EXPECT_LE(std::fabs(loop - ref), 1e-5 * (std::fabs(ref) + scale)) << what << " of particle " << id << ": loop "
                                                                     << loop << " vs direct " << ref;
}

TEST_P(HydroBruteForce, LoopsMatchDirectSummation) {
  const Case c = GetParam();
  std::mt19937_64 rng(42 + static_cast<int>(c.setup));
  GasParticles g;
  Vec3 box{1, 1, 1};
  bool periodic = true;
  switch (c.setup) {
    case Setup::UniformPeriodic:
      test::add_random(g, 1500, {0, 0, 0}, box, 1.0 / 1500, 1.0, 1.0, rng);
      break;
    case Setup::ClumpInHotGas:
      test::add_random(g, 1200, {0, 0, 0}, box, 1.0 / 1200, 100.0, 1.0, rng);
      test::add_random(g, 400, {0.42, 0.42, 0.42}, {0.16, 0.16, 0.16}, 1.0 / 1200, 1.0, 0.2, rng);
      break;
    case Setup::MixedActive:
      test::add_random(g, 800, {0, 0, 0}, box, 1.0 / 1500, 1.0, 1.0, rng);
      test::add_random(g, 700, {0, 0, 0}, {0.4, 1, 1}, 1.0 / 1500, 1.0, 1.0, rng);  // density step: mixed h
      break;
    case Setup::NearBoundaries:
      test::add_random(g, 700, {0, 0, 0}, {0.12, 1, 1}, 1.0 / 1500, 1.0, 1.0, rng);
      test::add_random(g, 700, {0.88, 0, 0}, {0.12, 1, 1}, 1.0 / 1500, 1.0, 1.0, rng);
      test::add_random(g, 300, {0, 0, 0}, {0.1, 0.1, 0.1}, 1.0 / 1500, 5.0, 1.0, rng);
      break;
    case Setup::OpenBoundaries:
      periodic = false;
      test::add_random(g, 1200, {0, 0, 0}, box, 1.0 / 1200, 100.0, 1.0, rng);
      test::add_random(g, 300, {0.3, 0.3, 0.3}, {0.1, 0.1, 0.1}, 1.0 / 1200, 1.0, 0.2, rng);
      break;
  }
  RunConfig cfg = test::test_config(periodic, box, c.msph);
  cfg.hydro.viscosity_reconstruction = c.reconstruction;
  // The loops find the signal velocity only for the criterion that reads it.
  cfg.hydro.courant_criterion = CourantCriterion::SignalVelocity;
  Engine engine(cfg, g);
  // First pass: every particle active, so all have densities the MSPH rule can compare.
  engine.compute_hydro_at(0);
  if (c.setup == Setup::MixedActive) {
    std::uniform_int_distribution<int> bin(0, 3);
    for (auto& b : engine.gas().time_bin) b = static_cast<TimeBin>(bin(rng));
  }
  // ti = 4 ticks: bins 0-2 are active, bin 3 is not; positions move by a negligible drift.
  const IntegerTime ti = c.setup == Setup::MixedActive ? 4 : 0;
  engine.compute_hydro_at(ti);

  const GasParticles& gas = engine.gas();
  const test::BruteForce bf{gas, cfg.hydro, periodic, box};
  double div_scale = 0, curl_scale = 0, a_scale = 0, du_scale = 0, strain_scale = 0;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    strain_scale += norm(gas.strain_diagonal[i]) + norm(gas.strain_shear[i]);
    div_scale += std::fabs(gas.div_v[i]);
    curl_scale += norm(gas.curl_v[i]);
    a_scale += norm(gas.a_hydro[i]);
    du_scale += std::fabs(gas.du_dt[i]);
  }
  const double n = static_cast<double>(gas.size());
  div_scale /= n, curl_scale /= n, a_scale /= n, du_scale /= n, strain_scale /= n;
  // The strain rate is worked out only for the reconstruction, and then for every particle.
  if (c.reconstruction) EXPECT_GT(strain_scale, 0.0);
  else EXPECT_EQ(strain_scale, 0.0);

  std::size_t checked = 0, inactive = 0;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    if (!TimeLine::active(gas.time_bin[i], ti)) {
      ++inactive;
      continue;
    }
    ++checked;
    const auto ref = bf.density(i, gas.h[i]);
    EXPECT_NEAR(ref.wcount, cfg.hydro.neighbours, cfg.hydro.neighbours_tolerance * 1.0001) << "particle " << gas.id[i];
    expect_close(gas.wcount[i], ref.wcount, 0.0, "neighbour number", gas.id[i]);
    expect_close(gas.rho[i], ref.rho, 0.0, "density", gas.id[i]);
    expect_close(gas.div_v[i], ref.div_v, div_scale, "div v", gas.id[i]);
    for (int k = 0; k < 3; ++k) expect_close(gas.curl_v[i][k], ref.curl_v[k], curl_scale, "curl v", gas.id[i]);
    if (i % 7 == 0) expect_close(gas.h[i], bf.solve_h(i, gas.h[i]), 0.0, "h", gas.id[i]);
    if (c.reconstruction) {
      const hydro::StrainRate s = bf.strain(i, gas.h[i]);
      for (int k = 0; k < 3; ++k) {
        expect_close(gas.strain_diagonal[i][k], s.diagonal[k], strain_scale, "strain rate", gas.id[i]);
        expect_close(gas.strain_shear[i][k], s.shear[k], strain_scale, "strain rate", gas.id[i]);
      }
    }
    const auto f = bf.force(i);
    for (int k = 0; k < 3; ++k) expect_close(gas.a_hydro[i][k], f.a[k], a_scale, "acceleration", gas.id[i]);
    expect_close(gas.du_dt[i], f.du_dt, du_scale, "du/dt", gas.id[i]);
    // The signal velocity the signal-velocity Courant criterion reads: the largest over the
    // coupled pairs, and at least 2 c_i.
    const double c_i = hydro::sound_speed(gas.rho[i], gas.u[i], cfg.hydro.gamma);
    EXPECT_NEAR(gas.v_sig[i], std::max(f.v_sig, 2.0 * c_i), 1e-12 * gas.v_sig[i]) << "v_sig of particle " << gas.id[i];
    EXPECT_GE(f.v_sig, c_i) << "particle " << gas.id[i] << " has no force pair";
    if (::testing::Test::HasFailure()) break;  // one particle's report is enough
  }
  EXPECT_GT(checked, gas.size() / 2);
  if (c.setup == Setup::MixedActive) {
    EXPECT_GT(inactive, gas.size() / 10);
  }
  // The clump set-ups are where the MSPH rule must fire, and only when it is on.
  if (c.setup == Setup::ClumpInHotGas || c.setup == Setup::OpenBoundaries) {
    if (c.msph) {
      EXPECT_GT(bf.decoupled_pairs(), 100u);
      EXPECT_GE(engine.msph_decoupled(), static_cast<long long>(bf.decoupled_pairs()));  // the force loop's own count
    } else {
      EXPECT_EQ(bf.decoupled_pairs(), 0u);
      EXPECT_EQ(engine.msph_decoupled(), 0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllSetups, HydroBruteForce,
                         testing::Values(Case{Setup::UniformPeriodic, false}, Case{Setup::UniformPeriodic, true},
                                         Case{Setup::ClumpInHotGas, false}, Case{Setup::ClumpInHotGas, true},
                                         Case{Setup::MixedActive, false}, Case{Setup::MixedActive, true},
                                         Case{Setup::NearBoundaries, false}, Case{Setup::NearBoundaries, true},
                                         Case{Setup::OpenBoundaries, false}, Case{Setup::OpenBoundaries, true},
                                         Case{Setup::UniformPeriodic, true, true}, Case{Setup::ClumpInHotGas, true, true},
                                         Case{Setup::MixedActive, false, true}),
                         name);

// The floor of h (hydro.h_min_ratio): a particle whose neighbour number would need a smaller
// h keeps the floor, with its density, neighbour number and forces those of the floor's
// kernel (checked against direct sums); particles above the floor are untouched.
TEST(SmoothingLengthFloor, HeldParticlesTakeTheFloorsKernel) {
  std::mt19937_64 rng(7);
  GasParticles g;
  test::add_random(g, 1200, {0, 0, 0}, {1, 1, 1}, 1.0 / 1200, 1.0, 1.0, rng);
  test::add_random(g, 400, {0.42, 0.42, 0.42}, {0.16, 0.16, 0.16}, 1.0 / 1200, 1.0, 0.2, rng);
  RunConfig cfg = test::test_config(true, {1, 1, 1}, false);
  cfg.hydro.courant_criterion = CourantCriterion::SignalVelocity;
  const GasParticles start = g;
  Engine free_engine(cfg, g);
  free_engine.compute_hydro_at(0);
  const GasParticles& free = free_engine.gas();
  std::vector<double> hs(free.h.begin(), free.h.end());
  std::sort(hs.begin(), hs.end());
  // A floor above the clump's kernels and below the diffuse gas's.
  const double floor = hs[hs.size() / 8];
  ASSERT_GT(floor, 1.2 * hs.front());
  ASSERT_LT(floor, 0.8 * hs.back());

  cfg.hydro.h_min = floor;
  Engine engine(cfg, start);
  engine.compute_hydro_at(0);
  engine.compute_hydro_at(0);  // a second solve starts from particles already at the floor
  const GasParticles& gas = engine.gas();
  const test::BruteForce bf{gas, cfg.hydro, true, {1, 1, 1}};
  std::size_t held = 0;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    ASSERT_EQ(gas.id[i], free.id[i]);
    ASSERT_GE(gas.h[i], floor) << "particle " << gas.id[i];
    if (free.h[i] < floor) {
      ++held;
      EXPECT_EQ(gas.h[i], floor) << "particle " << gas.id[i];
      const auto ref = bf.density(i, floor);
      EXPECT_GT(ref.wcount, cfg.hydro.neighbours) << "particle " << gas.id[i];
      expect_close(gas.wcount[i], ref.wcount, 0.0, "neighbour number", gas.id[i]);
      expect_close(gas.rho[i], ref.rho, 0.0, "density", gas.id[i]);
      const auto f = bf.force(i);
      for (int k = 0; k < 3; ++k) expect_close(gas.a_hydro[i][k], f.a[k], norm(f.a), "acceleration", gas.id[i]);
      expect_close(gas.du_dt[i], f.du_dt, std::fabs(f.du_dt), "du/dt", gas.id[i]);
    } else if (free.h[i] > 1.01 * floor) {
      // Converged to the same neighbour number; the floor's neighbours differ only in their
      // own h, so h agrees to the solver's tolerance.
      EXPECT_NEAR(gas.h[i], free.h[i], 1e-6 * free.h[i]) << "particle " << gas.id[i];
    }
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_GT(held, gas.size() / 10);
  EXPECT_GT(engine.h_min_held(), 0);
  EXPECT_EQ(free_engine.h_min_held(), 0);
  // Steps with some particles inactive: the drift's prediction of h keeps to the floor too.
  engine.initialise();
  for (int step = 0; step < 20; ++step) {
    engine.step();
    for (std::size_t i = 0; i < gas.size(); ++i) ASSERT_GE(gas.h[i], floor) << "particle " << gas.id[i] << ", step " << step;
  }
}

// Gas in one corner of the unit box and dark matter alone in the opposite one, so that some
// leaves hold no gas. Dark matter needs gravity; G = 1 with total mass 1.4 is weak beside the
// gas's motions.
struct GasBesideDarkMatter {
  GasParticles gas;
  CollisionlessParticles dm;
  RunConfig cfg;
};

GasBesideDarkMatter gas_beside_dark_matter(bool msph) {
  GasBesideDarkMatter set;
  std::mt19937_64 rng(11);
  test::add_random(set.gas, 1000, {0, 0, 0}, {0.5, 0.5, 0.5}, 1.0 / 1000, 1.0, 1.0, rng);
  set.dm.resize(400);
  std::uniform_real_distribution<double> U(0.6, 0.95);
  for (std::size_t k = 0; k < set.dm.size(); ++k) {
    set.dm.id[k] = 5000 + k;
    set.dm.mass[k] = 1e-3;
    set.dm.x[k] = {U(rng), U(rng), U(rng)};
  }
  set.cfg = test::test_config(false, {1, 1, 1}, msph);
  set.cfg.gravity.enabled = true;
  set.cfg.gravity.softening_dark_matter = 0.02;
  set.cfg.gravity.softening_gas = 0.01;
  return set;
}

bool has_gas_free_leaf(const Engine& engine) {
  for (int c : engine.space().leaves())
    if (engine.space().cell(c).count == 0) return true;
  return false;
}

// A leaf holding only dark matter has no SPH neighbours to cover: it must not ask for a
// rebuild whenever gas moves (it did, at every step, once the collapsing sphere's halo had
// such leaves: a sixth of a long run went into recutting the cells).
TEST(CellCover, GasFreeLeavesDoNotForceRebuilds) {
  const GasBesideDarkMatter set = gas_beside_dark_matter(false);
  Engine engine(set.cfg, set.gas, set.dm);
  engine.initialise();
  ASSERT_TRUE(has_gas_free_leaf(engine));
  int steps = 0, rebuilt = 0;
  for (; steps < 30; ++steps) rebuilt += engine.step().rebuilt ? 1 : 0;
  // The gas moves ~0.5 per unit time against h ~ 0.1 with a skin of 0.25 h: a rebuild every
  // few steps at most, never at every one.
  EXPECT_LT(rebuilt, steps / 2) << rebuilt << " of " << steps << " steps rebuilt";
}

// Gas-only tasks (density, ghost, force, cooling, star formation, feedback search) are not
// made for a leaf without gas; every module's links must then add no dependency on them.
// (Star formation's once linked every leaf, and a leaf without gas gave an edge from task -1
// that corrupted the heap as the graph was sorted.)
TEST(CellCover, GasFreeLeavesGetNoGasTasksOrEdges) {
  GasBesideDarkMatter set = gas_beside_dark_matter(true);
  set.cfg.star_formation.enabled = true;
  Engine engine(set.cfg, set.gas, set.dm);
  engine.initialise();
  ASSERT_TRUE(has_gas_free_leaf(engine));
  for (int step = 0; step < 5; ++step) EXPECT_NO_THROW(engine.step()) << "step " << step;
}

// A leaf's surroundings are exactly the other leaves with gas whose boxes lie within twice
// its cover: the rebuild check relies on every other leaf being at least that far.
TEST(CellCover, SurroundingsAreTheLeavesWithinTwiceTheCover) {
  std::mt19937_64 rng(3);
  GasParticles g;
  test::add_random(g, 1200, {0, 0, 0}, {1, 1, 1}, 1.0 / 1500, 1.0, 1.0, rng);
  test::add_random(g, 600, {0.6, 0.1, 0.2}, {0.1, 0.1, 0.1}, 1.0 / 1500, 1.0, 1.0, rng);
  Engine engine(test::test_config(true, {1, 1, 1}, false), g);
  engine.initialise();
  const Space& space = engine.space();
  std::size_t listed = 0;
  for (int a : space.leaves()) {
    if (space.cell(a).count == 0) continue;
    const auto& around = space.surroundings(a);
    for (int b : space.leaves()) {
      if (b == a || space.cell(b).count == 0) continue;
      const bool within = space.box_distance(space.cell(a), space.cell(b)) < Space::surroundings_reach(space.cell(a));
      const bool in_list = std::find(around.begin(), around.end(), b) != around.end();
      EXPECT_EQ(within, in_list) << "leaves " << a << " and " << b;
    }
    listed += around.size();
  }
  EXPECT_GT(listed, 0u);
}

// Between rebuilds the loops must still find every neighbour: after each step that did not
// rebuild, the densities of the particles active in it match direct sums over all particles.
TEST(CellCover, NeighboursStayCompleteBetweenRebuilds) {
  std::mt19937_64 rng(17);
  GasParticles g;
  test::add_random(g, 1000, {0, 0, 0}, {1, 1, 1}, 1.0 / 1500, 0.02, 6.0, rng);      // sparse and fast
  test::add_random(g, 500, {0.3, 0.3, 0.3}, {0.15, 0.15, 0.15}, 1.0 / 1500, 0.05, 0.0, rng);  // dense, at rest
  const RunConfig cfg = test::test_config(true, {1, 1, 1}, false);
  Engine engine(cfg, g);
  engine.initialise();
  int quiet_steps = 0;
  std::size_t checked = 0;
  for (int step = 0; step < 40 && !::testing::Test::HasFailure(); ++step) {
    if (engine.step().rebuilt) continue;
    ++quiet_steps;
    engine.drift_all();  // the positions the loops saw, for the direct sums
    const GasParticles& gas = engine.gas();
    const test::BruteForce bf{gas, cfg.hydro, true, {1, 1, 1}};
    for (std::size_t i = 0; i < gas.size(); ++i) {
      if (gas.ti_begin[i] != engine.ti_current()) continue;  // not active in this step
      ++checked;
      expect_close(gas.rho[i], bf.density(i, gas.h[i]).rho, 0.0, "density", gas.id[i]);
      if (::testing::Test::HasFailure()) break;
    }
  }
  EXPECT_GT(quiet_steps, 5);
  EXPECT_GT(checked, 500u);
}

// A recut leaves the derived fields (force inputs, MSPH copies, Courant bins) where they were
// (GasParticles::Derived): nothing may read them in a step before its drift tasks and ghosts
// work them out. Poisoned after every rebuild (NaN, and the shortest bin, which the timestep
// limiter would act on), a run must stay bitwise the one left alone: with and without the
// MSPH rule, whose density loop reads a neighbour's sound speed.
TEST(DerivedFields, NothingReadsThemAfterARecutBeforeTheStepWorksThemOut) {
  for (const bool msph : {false, true}) {
    std::mt19937_64 rng(29);
    GasParticles g;
    test::add_random(g, 800, {0, 0, 0}, {1, 1, 1}, 1.0 / 1200, 0.02, 6.0, rng);
    test::add_random(g, 400, {0.3, 0.3, 0.3}, {0.15, 0.15, 0.15}, 1.0 / 1200, 0.5, 0.0, rng);
    RunConfig cfg = test::test_config(true, {1, 1, 1}, msph);
    cfg.hydro.timestep_limiter = true;
    Engine plain(cfg, g), poisoned(cfg, g);
    int rebuilds = 0;
    poisoned.set_after_rebuild([&] {
      ++rebuilds;
      GasParticles& p = poisoned.gas();
      const double nan = std::numeric_limits<double>::quiet_NaN();
      for (auto* f : {&p.soundspeed, &p.p_over_rho_a, &p.inv_rho_2ma, &p.balsara, &p.rho_msph, &p.h_msph})
        std::fill(f->begin(), f->end(), nan);
      std::fill(p.courant_bin.begin(), p.courant_bin.end(), TimeBin{0});
    });
    plain.initialise();
    poisoned.initialise();
    for (int step = 0; step < 60; ++step) {
      plain.step();
      poisoned.step();
    }
    EXPECT_GE(rebuilds, 3) << "msph " << msph;
    plain.drift_all();
    poisoned.drift_all();
    const GasParticles &a = plain.gas(), &b = poisoned.gas();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(std::memcmp(&a.x[i], &b.x[i], sizeof(Vec3)), 0) << "msph " << msph << ", particle " << a.id[i];
      ASSERT_EQ(std::memcmp(&a.v_full[i], &b.v_full[i], sizeof(Vec3)), 0) << "particle " << a.id[i];
      ASSERT_EQ(std::memcmp(&a.u_full[i], &b.u_full[i], sizeof(double)), 0) << "particle " << a.id[i];
      ASSERT_EQ(std::memcmp(&a.rho[i], &b.rho[i], sizeof(double)), 0) << "particle " << a.id[i];
      ASSERT_EQ(a.time_bin[i], b.time_bin[i]) << "particle " << a.id[i];
    }
  }
}

// The gravity tree must follow the particles to every step's positions. A step with no
// active particle (a drift to an output time) right after a recut once left the next step's
// walks on the tree of that recut: the decision to refit was taken by the tree task, which
// such a step never runs. With every node opened (alpha_force 0) the walk is a direct sum
// over the tree's copies of the particles, so a stale copy shows as an error of order
// (motion since the recut) / (separation), far above float's 1e-6.
TEST(GravityTreeInEngine, FollowsTheParticlesAfterAStepWithNoneActive) {
  std::mt19937_64 rng(23);
  GasParticles g;
  test::add_random(g, 500, {0, 0, 0}, {1, 1, 1}, 1.0 / 500, 0.01, 3.0, rng);
  RunConfig cfg = test::test_config(false, {1, 1, 1}, false);
  cfg.gravity.enabled = true;
  cfg.gravity.softening_gas = 0.01;
  cfg.gravity.alpha_force = 0.0;
  cfg.gravity.theta = 1e-9;
  Engine engine(cfg, g);
  engine.initialise();
  for (int k = 0; k < 3; ++k) engine.step();
  engine.rebuild_now();
  IntegerTime ti_next = TimeLine::ticks;
  for (int c : engine.space().leaves()) ti_next = std::min(ti_next, engine.space().cell(c).ti_end_min);
  ASSERT_GT(ti_next, engine.ti_current() + 1);
  EXPECT_EQ(engine.step(engine.ti_current() + (ti_next - engine.ti_current()) / 2).active, 0u);
  ASSERT_GT(engine.step().active, 0u);
  const GasParticles& gas = engine.gas();
  std::vector<double> mass(gas.size()), eps(gas.size(), cfg.gravity.softening_gas);
  for (std::size_t i = 0; i < gas.size(); ++i) mass[i] = gas.dynamical_mass(i);
  double worst = 0.0;
  std::size_t checked = 0;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    if (gas.ti_begin[i] != engine.ti_current()) continue;  // not walked in the last step
    const gravity::GravityTarget t{gas.x[i], cfg.gravity.softening_gas, gravity::kNoOldAcceleration,
                                   static_cast<std::int64_t>(i)};
    const gravity::GravityResult d = gravity::direct_on_target(t, gas.x, mass, eps, cfg.gravity.G);
    worst = std::max(worst, norm(gas.a_grav[i] - d.acceleration) / norm(d.acceleration));
    ++checked;
  }
  EXPECT_GT(checked, 0u);
  EXPECT_LT(worst, 1e-5) << "over " << checked << " particles walked in the step after";
}

// Gravity in a periodic box is TreePM: after the first force computation every particle's
// acceleration (mesh plus tree, relative criterion from the first pass) is its exact periodic
// acceleration from Ewald summation, to the split's accuracy (docs/gravity.md: at r_s = 1.25
// cells the median error is a few 1e-3 on random sets), where an open tree leaves out the
// periodic images. Runs on 1 and 2 threads are the same bits.
TEST(GravityTreeInEngine, PeriodicBoxesGetTreePMForces) {
  std::mt19937_64 rng(31);
  GasParticles g;
  test::add_random(g, 1500, {0, 0, 0}, {1, 1, 1}, 1.0 / 2000, 0.01, 0.0, rng);
  test::add_random(g, 500, {0.55, 0.2, 0.35}, {0.1, 0.1, 0.1}, 1.0 / 2000, 0.01, 0.0, rng);
  for (std::size_t i = 0; i < g.size(); ++i) g.id[i] = i + 1;
  std::vector<GasParticles> runs;
  for (const int threads : {1, 2}) {
    RunConfig cfg = test::test_config(true, {1, 1, 1}, false, threads);
    cfg.gravity.enabled = true;
    cfg.gravity.softening_gas = 0.002;
    cfg.gravity.mesh_cells = 32;
    Engine engine(cfg, g);
    engine.initialise();
    for (int k = 0; k < 4; ++k) engine.step();
    runs.push_back(engine.gas());
    if (threads != 1) continue;
    // The first force computation, checked on a fresh engine.
    Engine first(cfg, g);
    first.initialise();
    const GasParticles& gas = first.gas();
    std::vector<double> mass(gas.size()), eps(gas.size(), cfg.gravity.softening_gas);
    for (std::size_t i = 0; i < gas.size(); ++i) mass[i] = gas.dynamical_mass(i);
    std::vector<std::size_t> targets;
    for (std::size_t i = 0; i < gas.size(); i += 10) targets.push_back(i);
    const std::vector<Vec3> exact = gravity::ewald_accelerations(gas.x, mass, eps, 1.0, cfg.gravity.G, targets);
    std::vector<double> errors;
    for (std::size_t t = 0; t < targets.size(); ++t)
      errors.push_back(norm(gas.a_grav[targets[t]] - exact[t]) / norm(exact[t]));
    std::sort(errors.begin(), errors.end());
    EXPECT_LE(errors[errors.size() / 2], 5e-3);
    EXPECT_LE(errors[errors.size() * 99 / 100], 3e-2);
    std::printf("engine TreePM against Ewald: median %.2e, 99th %.2e over %zu particles\n", errors[errors.size() / 2],
                errors[errors.size() * 99 / 100], errors.size());
  }
  const GasParticles &a = runs[0], &b = runs[1];
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(std::memcmp(&a.x[i], &b.x[i], sizeof(Vec3)), 0) << "particle " << a.id[i];
    ASSERT_EQ(std::memcmp(&a.a_grav[i], &b.a_grav[i], sizeof(Vec3)), 0) << "particle " << a.id[i];
  }
}

}  // namespace
}  // namespace fountain
