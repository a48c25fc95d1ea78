// The SPH kernel and the pure pair interactions, tested alone.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "hydro/HydroIact.hpp"
#include "hydro/Kernel.hpp"
#include "hydro/SmoothingLengthSolve.hpp"

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

// A particle at the edge of a tight clump (the 69 candidates of one such particle in the
// collapsed centre of the 8000-per-species sphere, distances in units of 1e-4 Mpc/h): N(h) is
// S-shaped there, and plain Newton steps inside the bracket jump between its ends for ever.
// The solver must converge to the root a bisection of N(h) finds.
TEST(SmoothingLengthSolve, ConvergesAtTheEdgeOfATightClump) {
  const double radii[] = {
      0.000000e+00, 2.227056e-01, 2.776486e-01, 3.327383e-01, 3.450846e-01, 3.481833e-01,
      4.228543e-01, 4.341974e-01, 4.376144e-01, 4.575068e-01, 4.903263e-01, 4.982782e-01,
      5.090953e-01, 5.795566e-01, 6.431543e-01, 6.845206e-01, 6.863447e-01, 7.479277e-01,
      7.826085e-01, 7.980140e-01, 8.788835e-01, 9.823679e-01, 1.037102e+00, 1.049616e+00,
      1.124074e+00, 1.209347e+00, 1.229152e+00, 1.320837e+00, 1.353441e+00, 1.457068e+00,
      1.459738e+00, 1.550399e+00, 1.686569e+00, 1.704264e+00, 1.765368e+00, 1.795886e+00,
      1.819613e+00, 1.819788e+00, 1.853758e+00, 1.858586e+00, 1.969162e+00, 1.970320e+00,
      2.039781e+00, 2.112822e+00, 2.135357e+00, 2.174141e+00, 2.197334e+00, 2.207468e+00,
      2.274915e+00, 2.313345e+00, 2.337890e+00, 2.347054e+00, 2.462249e+00, 2.480100e+00,
      2.494733e+00, 2.506696e+00, 2.537519e+00, 2.568239e+00, 2.584864e+00, 2.649168e+00,
      2.679956e+00, 2.702347e+00, 2.739871e+00, 2.791820e+00, 2.802271e+00, 2.838488e+00,
      2.870474e+00, 2.945171e+00, 3.116841e+00};
  hydro::DensityPairs pairs;
  pairs.reset(std::size(radii));
  for (double r : radii) pairs.add({r * 1e-4, 0.0, 0.0}, {}, r * r * 1e-8, 1.0);
  auto density_at = [&](double h) { return hydro::finish_density(hydro::sum_density_pairs(pairs, h), h); };
  HydroParams p;  // N_ngb = 32 +- 1, 50 iterations
  const double h0 = 2.5008362695538367e-4, reach = 3.126045336942296e-4;

  // The old rule (Newton when inside the bracket, else halve it) cycles here.
  double lo = 0.0, hi = reach, h = h0;
  bool plain_converged = false;
  for (int it = 0; it < p.max_h_iterations && !plain_converged; ++it) {
    const auto d = density_at(h);
    const double f = d.wcount - p.neighbours;
    plain_converged = std::fabs(f) <= p.neighbours_tolerance;
    (f < 0.0 ? lo : hi) = h;
    const double next = d.wcount_dh > 0.0 ? h - f / d.wcount_dh : -1.0;
    h = next > lo && next < hi ? next : 0.5 * (lo + hi);
  }
  EXPECT_FALSE(plain_converged);

  const auto solved = hydro::solve_smoothing_length(density_at, h0, reach, p);
  ASSERT_TRUE(solved.converged);
  EXPECT_NEAR(solved.density.wcount, p.neighbours, p.neighbours_tolerance);
  double a = 0.0, b = reach;
  for (int it = 0; it < 200; ++it) (density_at(0.5 * (a + b)).wcount < p.neighbours ? a : b) = 0.5 * (a + b);
  EXPECT_NEAR(solved.h, a, 0.02 * a);  // within the tolerance of one neighbour in 32
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
