// The SPH kernel and the pure pair interactions, tested alone.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

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

TEST(Timestep, CourantCriterion) {
  const HydroParams p = params(false);
  EXPECT_DOUBLE_EQ(hydro::courant_timestep(0.5, 0.0, 2.0, 1.0, p), 0.1 * 0.5 / (2.0 * (1 + 0.6 * 1.3)));
  EXPECT_DOUBLE_EQ(hydro::courant_timestep(0.5, -4.0, 2.0, 3.0, p), 0.1 * 0.5 / (2.0 + 3.0 * (1 + 0.6 * 1.3)));
}

}  // namespace
}  // namespace fountain
