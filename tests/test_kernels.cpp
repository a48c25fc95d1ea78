// The SPH kernel and the pure pair interactions, tested alone.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "hydro/HydroIact.hpp"
#include "hydro/Kernel.hpp"

namespace fountain {
namespace {

TEST(Kernel, NormalisedToOne) {
  const double h = 0.7;
  double integral = 0.0;
  const int n = 200000;
  for (int k = 0; k < n; ++k) {
    const double r = (k + 0.5) * h / n;
    integral += 4.0 * std::numbers::pi * r * r * kernel::value(r, 1.0 / h) * h / n;
  }
  EXPECT_NEAR(integral, 1.0, 1e-9);
  EXPECT_EQ(kernel::value(h, 1.0 / h), 0.0);
  EXPECT_EQ(kernel::value(1.5 * h, 1.0 / h), 0.0);
}

TEST(Kernel, DerivativesMatchFiniteDifferences) {
  const double h = 1.3;
  for (double q : {0.1, 0.3, 0.49, 0.51, 0.7, 0.95}) {
    const double r = q * h, e = 1e-6;
    const double fd_r = (kernel::value(r + e, 1 / h) - kernel::value(r - e, 1 / h)) / (2 * e);
    EXPECT_NEAR(kernel::derivative(r, 1 / h), fd_r, 1e-6 * std::fabs(fd_r) + 1e-9) << "q = " << q;
    double w, dw;
    kernel::eval(r, 1 / h, w, dw);
    const double fd_h = (kernel::value(r, 1 / (h + e)) - kernel::value(r, 1 / (h - e))) / (2 * e);
    EXPECT_NEAR(kernel::dh(r, 1 / h, w, dw), fd_h, 1e-6 * std::fabs(fd_h) + 1e-9) << "q = " << q;
  }
}

HydroParams params(bool msph) {
  HydroParams p;
  p.msph = msph;
  return p;
}

TEST(MsphRule, DecouplesDenseColdNeighbourUnlessShocking) {
  const HydroParams p = params(true);
  const hydro::MsphState hot{1.0, 100.0, 0.1, 10.0}, cold{20.0, 1.0, 0.05, 1.0};
  const Vec3 dx{0.05, 0, 0};
  const double r2 = dot(dx, dx);
  EXPECT_TRUE(hydro::msph_decoupled(hot, cold, dx, {0, 0, 0}, r2, p));
  EXPECT_TRUE(hydro::msph_decoupled(cold, hot, -dx, {0, 0, 0}, r2, p));  // symmetric
  // Approaching fast enough that mu_ij < -c_ij: a shock, so they stay coupled.
  EXPECT_FALSE(hydro::msph_decoupled(hot, cold, dx, {-200.0, 0, 0}, r2, p));
  // Density contrast below A, or energy contrast below A': coupled.
  EXPECT_FALSE(hydro::msph_decoupled(hot, {9.0, 1.0, 0.05, 1.0}, dx, {}, r2, p));
  EXPECT_FALSE(hydro::msph_decoupled(hot, {20.0, 20.0, 0.05, 1.0}, dx, {}, r2, p));
  // Switched off: never.
  EXPECT_FALSE(hydro::msph_decoupled(hot, cold, dx, {}, r2, params(false)));
}

TEST(ForcePair, AntisymmetricAndEnergyConserving) {
  const HydroParams p = params(false);
  const auto a = hydro::make_force_state({1.0, 0.2, -0.3}, 2.0, 1.3, 2.0, 0.5, -0.4, {0.1, 0.2, 0.3}, p);
  const auto b = hydro::make_force_state({-0.5, 0.1, 0.4}, 1.5, 0.7, 3.0, 0.6, -0.2, {0.0, 0.1, 0.0}, p);
  const Vec3 dx{0.2, -0.1, 0.15};
  hydro::ForceSums sa, sb;
  hydro::iact_force(a, b, dx, dot(dx, dx), p, sa);
  hydro::iact_force(b, a, -dx, dot(dx, dx), p, sb);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.m * sa.a[k] + b.m * sb.a[k], 0.0, 1e-15 * std::fabs(a.m * sa.a[k]));
  // d/dt (kinetic + thermal) of the pair is zero for the paper's equations.
  const double de = a.m * dot(a.v, sa.a) + b.m * dot(b.v, sb.a) + a.m * sa.du_dt + b.m * sb.du_dt;
  EXPECT_NEAR(de, 0.0, 1e-14 * std::fabs(a.m * sa.du_dt));
}

TEST(ForcePair, ViscosityOnlyWhenApproaching) {
  HydroParams p = params(false);
  auto state = [&](Vec3 v) { return hydro::make_force_state(v, 1.0, 1.0, 1.0, 0.5, -1.0, {}, p); };
  const Vec3 dx{0.2, 0, 0};
  hydro::ForceSums receding, approaching;
  hydro::iact_force(state({1, 0, 0}), state({-1, 0, 0}), dx, dot(dx, dx), p, receding);
  hydro::iact_force(state({-1, 0, 0}), state({1, 0, 0}), dx, dot(dx, dx), p, approaching);
  // Approaching pairs are pushed apart harder (viscous pressure adds to the thermal one).
  EXPECT_GT(approaching.a.x, receding.a.x);
  EXPECT_GT(approaching.du_dt, 0.0);
}

// The four-pair forms the loops use must give what the one-pair forms give.
TEST(PairLanes, DensityMatchesOnePairForm) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const double h = 0.9;
  hydro::DensitySums one;
  hydro::DensityPairs q;
  q.reset(403);
  int inside = 0;
  for (int k = 0; k < 403; ++k) {
    const Vec3 dx = k == 0 ? Vec3{} : Vec3{uni(rng), uni(rng), uni(rng)} * 0.6;  // one self pair (r = 0)
    const Vec3 dv{uni(rng), uni(rng), uni(rng)};
    const double r2 = dot(dx, dx), m = 1.0 + 0.5 * uni(rng);
    if (r2 >= h * h) continue;
    ++inside;
    hydro::iact_density(dx, dv, r2, 1.0 / h, m, one);
    q.add(dx, dv, r2, m);
  }
  ASSERT_GT(inside, 100);
  ASSERT_NE(inside % hydro::kLanes, 0);  // the padding of the last batch is exercised
  const hydro::DensitySums s = hydro::sum_density_pairs(q, h);
  const double tol = 1e-13;
  EXPECT_NEAR(s.rho, one.rho, tol * std::fabs(one.rho));
  EXPECT_NEAR(s.w, one.w, tol * std::fabs(one.w));
  EXPECT_NEAR(s.w_dh, one.w_dh, tol * std::fabs(one.w_dh));
  // div and curl sum terms of both signs: compare against the size of the density sum.
  const double scale = std::fabs(one.rho) / h;
  EXPECT_NEAR(s.div, one.div, 10 * tol * scale);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(s.curl[d], one.curl[d], 10 * tol * scale);
}

TEST(PairLanes, ForceMatchesOnePairForm) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const HydroParams p = params(false);
  auto state = [&] {
    const Vec3 v{uni(rng), uni(rng), uni(rng)};
    return hydro::make_force_state(v, 1.0 + 0.5 * uni(rng), 1.0 + 0.9 * uni(rng), 2.0 + uni(rng),
                                   0.5 + 0.2 * uni(rng), uni(rng), {uni(rng), uni(rng), uni(rng)}, p);
  };
  const hydro::ForceState fi = state();
  hydro::ForceSums one;
  hydro::ForcePairs q;
  q.reset(600);
  int pairs = 0;
  for (int k = 0; k < 600; ++k) {
    const hydro::ForceState fj = state();
    const Vec3 dx = Vec3{uni(rng), uni(rng), uni(rng)} * 0.7;
    const double r2 = dot(dx, dx);
    if (r2 >= fi.h * fi.h && r2 >= fj.h * fj.h) continue;
    ++pairs;
    hydro::iact_force(fi, fj, dx, r2, p, one);
    q.add(dx, fi.v - fj.v, r2, fj);
  }
  ASSERT_GT(pairs, 100);
  ASSERT_NE(pairs % hydro::kLanes, 0);  // the padding of the last batch is exercised
  const hydro::ForceSums s = hydro::sum_force_pairs<true>(fi, q, p);
  const hydro::ForceSums without = hydro::sum_force_pairs<false>(fi, q, p);
  EXPECT_EQ(without.a, s.a);  // the signal velocity changes nothing else
  EXPECT_EQ(without.du_dt, s.du_dt);
  const double scale = norm(one.a);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(s.a[d], one.a[d], 1e-12 * scale);
  EXPECT_NEAR(s.du_dt, one.du_dt, 1e-12 * std::fabs(one.du_dt));
  EXPECT_EQ(s.v_sig, one.v_sig);  // a maximum: the same pairs give the same value
  EXPECT_GT(one.v_sig, fi.c);
}

TEST(Timestep, CourantCriterion) {
  const HydroParams p = params(false);
  EXPECT_DOUBLE_EQ(hydro::courant_timestep(0.5, 0.0, 2.0, 1.0, p), 0.1 * 0.5 / (2.0 * (1 + 0.6 * 1.3)));
  EXPECT_DOUBLE_EQ(hydro::courant_timestep(0.5, -4.0, 2.0, 3.0, p), 0.1 * 0.5 / (2.0 + 3.0 * (1 + 0.6 * 1.3)));
}

TEST(Timestep, SignalVelocityCriterionMatchesThePapersAtRest) {
  HydroParams p = params(false);
  // Gas at rest: v_sig = c_i + c_j = 2c, and the two criteria give one step.
  const double h = 0.5, c = 2.0;
  EXPECT_DOUBLE_EQ(hydro::signal_velocity_timestep(h, hydro::signal_velocity(c, c, 0.0, 1.0), p),
                   hydro::courant_timestep(h, 0.0, c, 0.0, p));
  // Approaching pairs raise the signal velocity by 3 |w|; receding ones do not lower it.
  EXPECT_DOUBLE_EQ(hydro::signal_velocity(1.0, 2.0, -0.5, 2.0), 1.0 + 2.0 + 3.0);
  EXPECT_DOUBLE_EQ(hydro::signal_velocity(1.0, 2.0, 0.5, 2.0), 3.0);
  // The parameter picks the criterion.
  p.courant_criterion = CourantCriterion::SignalVelocity;
  EXPECT_DOUBLE_EQ(hydro::hydro_timestep(h, -4.0, c, 3.0, 10.0, p), hydro::signal_velocity_timestep(h, 10.0, p));
  p.courant_criterion = CourantCriterion::Syw;
  EXPECT_DOUBLE_EQ(hydro::hydro_timestep(h, -4.0, c, 3.0, 10.0, p), hydro::courant_timestep(h, -4.0, c, 3.0, p));
}

}  // namespace
}  // namespace fountain
