// The expanding background against closed forms (Einstein-de Sitter, flat LCDM) and reference values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "core/Error.hpp"
#include "cosmology/Background.hpp"
#include "cosmology/IntegrationFactors.hpp"
#include "step/TimeLine.hpp"

namespace fountain {
namespace {

using cosmology::Background;
using cosmology::CosmologyParams;
using cosmology::IntegrationFactors;

constexpr double H0 = cosmology::kHubbleInternal;

void expect_rel(double got, double want, double tol, const char* what) {
  EXPECT_LE(std::fabs(got / want - 1.0), tol) << what << ": " << got << " vs " << want;
}

CosmologyParams eds() {
  CosmologyParams p;
  p.omega_m = 1.0;
  p.omega_lambda = 0.0;
  return p;
}

TEST(CosmologyBackground, EinsteinDeSitterClosedForms) {
  const Background b(eds());
  for (double a : {0.01, 0.1, 0.5, 1.0}) {
    expect_rel(b.E(a), std::pow(a, -1.5), 1e-14, "E");
    expect_rel(b.cosmic_time(a), 2.0 / (3.0 * H0) * std::pow(a, 1.5), 1e-10, "t");
    expect_rel(b.growth(a), a, 1e-10, "D");
    expect_rel(b.growth_rate(a), 1.0, 1e-9, "f");
    const auto g2 = b.second_order_growth(a);
    expect_rel(g2.d2, -3.0 / 7.0 * a * a, 1e-8, "D2");
    expect_rel(g2.f2, 2.0, 1e-8, "f2");
  }
}

TEST(CosmologyBackground, FlatLcdmReferenceValues) {
  const Background b({0.3, 0.7, 0.04, 0.6});
  // Flat closed form of t(a), and the reference values to their quoted digits.
  for (double a : {0.02, 0.25, 0.5, 1.0}) {
    const double closed = 2.0 / (3.0 * H0 * std::sqrt(0.7)) * std::asinh(std::sqrt(0.7 / 0.3) * std::pow(a, 1.5));
    expect_rel(b.cosmic_time(a), closed, 1e-10, "t against asinh");
  }
  expect_rel(H0 * b.cosmic_time(1.0), 0.9640994, 1e-7, "H0 t0");
  expect_rel(b.cosmic_time(1.0 / 50.0), 3.44264e-5, 2e-6, "t(z = 49)");
  expect_rel(b.cosmic_time(0.25), 1.512355e-3, 5e-7, "t(z = 3)");
  expect_rel(b.cosmic_time(0.5), 4.117596e-3, 2e-7, "t(z = 1)");
  expect_rel(b.growth(1.0), 0.7789810168, 1e-8, "D(1)");
  expect_rel(b.growth_rate(1.0), 0.5127962477, 1e-8, "f(1)");
  expect_rel(b.growth(0.5), 0.4765850678, 1e-8, "D(0.5)");
  expect_rel(b.growth_rate(0.5), 0.8692851212, 1e-8, "f(0.5)");
  expect_rel(b.growth(0.02), 0.0199999321, 1e-8, "D(0.02)");
  expect_rel(b.growth_rate(0.02), 0.9999898183, 1e-8, "f(0.02)");
  auto d2_ratio = [&](double a) {
    const double d = b.growth(a);
    return b.second_order_growth(a).d2 / (-3.0 / 7.0 * d * d);
  };
  expect_rel(d2_ratio(1.0), 1.00863056, 1e-8, "D2 / (-3/7 D^2) at a = 1");
  expect_rel(d2_ratio(0.5), 1.00180799, 1e-8, "D2 / (-3/7 D^2) at a = 0.5");
  expect_rel(b.second_order_growth(1.0).f2, 1.04044783, 1e-8, "f2(1)");
  expect_rel(b.second_order_growth(0.5).f2, 1.74338939, 1e-8, "f2(0.5)");
}

// Curvature (Omega_m + Omega_L != 1): f against the derivative of D, D2's growth rate
// against its own derivative, and the time table against t(a).
TEST(CosmologyBackground, CurvedSelfConsistent) {
  const Background b({0.3, 0.5, 0.04, 0.7});
  EXPECT_NEAR(b.params().omega_k(), 0.2, 1e-15);
  for (double a : {0.05, 0.3, 1.0}) {
    const double e = 1e-4;
    const double fd = (std::log(b.growth(a * std::exp(e))) - std::log(b.growth(a * std::exp(-e)))) / (2.0 * e);
    expect_rel(b.growth_rate(a), fd, 1e-7, "f against dlnD/dlna");
    const double fd2 = (std::log(-b.second_order_growth(a * std::exp(e)).d2) -
                        std::log(-b.second_order_growth(a * std::exp(-e)).d2)) /
                       (2.0 * e);
    expect_rel(b.second_order_growth(a).f2, fd2, 1e-7, "f2 against dlnD2/dlna");
  }
  const IntegrationFactors k(b, 5.0 / 3.0, 0.05, 1.0);
  expect_rel(k.factor(IntegrationFactors::time, 0.05, 1.0), b.cosmic_time(1.0) - b.cosmic_time(0.05), 1e-10,
             "K_t against t(a)");
}

// A closed universe stops expanding where a^3 E^2 = Omega_m + Omega_k a + Omega_Lambda a^3
// first reaches zero: before a = 1 the background is refused; after it, a run past the limit.
TEST(CosmologyBackground, ExpansionLimit) {
  EXPECT_TRUE(std::isinf(Background(eds()).expansion_limit()));
  EXPECT_TRUE(std::isinf(Background({0.3, 0.7, 0.04, 0.7}).expansion_limit()));
  EXPECT_TRUE(std::isinf(Background({0.3, 0.5, 0.04, 0.7}).expansion_limit()));  // open
  EXPECT_TRUE(std::isinf(Background({2.5, 0.1, 0.04, 0.7}).expansion_limit()));   // closed, saved by Lambda
  EXPECT_NEAR(Background({3.0, 0.0, 0.04, 0.7}).expansion_limit(), 1.5, 1e-15);  // Omega_m / (Omega_m - 1)
  const Background closed({3.0, 0.1, 0.04, 0.7});
  const double limit = closed.expansion_limit();
  EXPECT_GT(limit, 1.0);
  EXPECT_LT(limit, 2.0);
  EXPECT_NEAR(3.0 - 2.1 * limit + 0.1 * limit * limit * limit, 0.0, 1e-13);
  EXPECT_NO_THROW(IntegrationFactors(closed, 5.0 / 3.0, 0.01, 0.99 * limit));
  EXPECT_THROW(IntegrationFactors(closed, 5.0 / 3.0, 0.01, 2.0), InputError);
  EXPECT_THROW(Background({0.3, 5.0, 0.04, 0.7}), InputError);  // would have bounced before a = 1
  EXPECT_THROW(Background({std::numeric_limits<double>::infinity(), 0.7, 0.04, 0.7}), InputError);
}

TEST(CosmologyFactors, EinsteinDeSitterClosedForms) {
  const Background b(eds());
  const IntegrationFactors k(b, 5.0 / 3.0, 0.01, 1.0);
  expect_rel(k.factor(IntegrationFactors::drift, 0.01, 1.0), 0.18, 1e-10, "K_d");
  expect_rel(k.factor(IntegrationFactors::hydro_kick, 0.01, 1.0), 0.18, 1e-10, "K_h");
  expect_rel(k.factor(IntegrationFactors::gravity_kick, 0.01, 1.0), 0.018, 1e-10, "K_g");
  expect_rel(k.factor(IntegrationFactors::time, 0.01, 1.0), 2.0 / 300.0 * (1.0 - 1e-3), 1e-10, "K_t");
  for (double a1 : {0.0123, 0.2, 0.77}) {
    const double a2 = a1 * std::exp(3e-3);
    expect_rel(k.factor(IntegrationFactors::drift, a1, a2), 2.0 / H0 * (1.0 / std::sqrt(a1) - 1.0 / std::sqrt(a2)),
               1e-10, "short K_d");
    expect_rel(k.factor(IntegrationFactors::gravity_kick, a1, a2), 2.0 / H0 * (std::sqrt(a2) - std::sqrt(a1)), 1e-10,
               "short K_g");
  }
}

TEST(CosmologyFactors, FlatLcdmAgainstQuadratureAndReferenceValues) {
  const Background b({0.3, 0.7, 0.04, 0.6});
  const IntegrationFactors k(b, 5.0 / 3.0, 0.02, 1.0);
  expect_rel(k.factor(IntegrationFactors::drift, 0.02, 1.0), 0.2163879, 5e-7, "K_d 0.02 -> 1");
  expect_rel(k.factor(IntegrationFactors::gravity_kick, 0.02, 1.0), 0.02788679, 5e-7, "K_g 0.02 -> 1");
  expect_rel(k.factor(IntegrationFactors::time, 0.02, 1.0), 9.606567e-3, 5e-7, "K_t 0.02 -> 1");
  expect_rel(k.factor(IntegrationFactors::drift, 0.5, 1.0), 0.01120458, 5e-7, "K_d 0.5 -> 1");
  expect_rel(k.factor(IntegrationFactors::gravity_kick, 0.5, 1.0), 7.714271e-3, 5e-7, "K_g 0.5 -> 1");
  expect_rel(k.factor(IntegrationFactors::time, 0.5, 1.0), 5.523398e-3, 5e-7, "K_t 0.5 -> 1");
  // The cosmic-time factor is t(a2) - t(a1); steps from 1e-5 to 0.02 in ln a against it.
  for (double a1 : {0.021, 0.1, 0.37, 0.9}) {
    for (double dlna : {1e-5, 1e-3, 0.02}) {
      const double a2 = a1 * std::exp(dlna);
      expect_rel(k.factor(IntegrationFactors::time, a1, a2), b.cosmic_time(a2) - b.cosmic_time(a1), 1e-8,
                 "K_t against t(a2) - t(a1)");
    }
  }
  // gamma = 5/3: the hydro kick is the drift.
  expect_rel(k.factor(IntegrationFactors::hydro_kick, 0.1, 0.3), k.factor(IntegrationFactors::drift, 0.1, 0.3), 1e-13,
             "K_h = K_d");
}

TEST(CosmologyFactors, StepsTelescopeAndTimeInverts) {
  const Background b({0.3, 0.7, 0.04, 0.6});
  const IntegrationFactors k(b, 5.0 / 3.0, 0.02, 1.0);
  double sum = 0.0, a = 0.02;
  const int steps = 4000;
  const double ratio = std::pow(1.0 / 0.02, 1.0 / steps);
  for (int i = 0; i < steps; ++i, a *= ratio) sum += k.factor(IntegrationFactors::drift, a, a * ratio);
  expect_rel(sum, k.factor(IntegrationFactors::drift, 0.02, a), 1e-13, "telescoping drift");
  for (double target : {0.03, 0.25, 0.5, 0.99}) {
    const double t = k.cumulative(IntegrationFactors::time, target);
    expect_rel(k.scale_factor_after(t), target, 1e-13, "a(t)");
  }
}

// The comoving leapfrog on the integer timeline in ln a, on the one problem whose exact
// solution it must follow: Zel'dovich's plane wave in Einstein-de Sitter before shell crossing
// (caustic at a_c = 1/2). Sheets at Lagrangian q feel -(1/a) dPhi'/dx = 4 pi G rhobar' (x - q)
// / a; exactly x = q - (a / a_c) sin(kq) / k and v' = -H0 a^(3/2) sin(kq) / (a_c k). Kick-drift-
// kick with the timeline's factors, 512 equal steps of ln a from a = 1/101 to 0.4 (z = 1.5),
// must reproduce it to 3e-5 of the amplitudes (an independent sheet model with 400 steps: 3e-5).
TEST(ComovingTimeLine, LeapfrogFollowsTheZeldovichPlaneWave) {
  const Background b(eds());
  const IntegrationFactors k(b, 5.0 / 3.0, 1.0 / 101.0, 0.4);
  const ComovingTimeLine line(k);
  const double box = 64.0, wave = 2.0 * std::numbers::pi / box, a_c = 0.5;
  const double four_pi_g_rho = 1.5 * H0 * H0;  // 4 pi G rhobar' = (3/2) H0^2 Omega_m
  const int sheets = 64;
  auto exact_x = [&](double qq, double a) { return qq - (a / a_c) * std::sin(wave * qq) / wave; };
  auto exact_v = [&](double qq, double a) { return -H0 * std::pow(a, 1.5) * std::sin(wave * qq) / (a_c * wave); };
  // The largest error in x and v' (in units of their amplitudes) after 2^(56 - bin) steps.
  auto errors = [&](int bin) {
    std::vector<double> q(sheets), x(sheets), v(sheets);
    for (int i = 0; i < sheets; ++i) {
      q[i] = (i + 0.5) * box / sheets - 0.5 * box;
      x[i] = exact_x(q[i], 1.0 / 101.0);
      v[i] = exact_v(q[i], 1.0 / 101.0);
    }
    const double step = std::ldexp(1.0, bin);
    for (IntegerTime ti = 0; ti < TimeLine::ticks; ti += TimeLine::step_ticks(bin)) {
      const double t0 = static_cast<double>(ti), mid = t0 + 0.5 * step, t1 = t0 + step;
      const double kick_open = line.gravity_kick(t0, mid), drift = line.drift(t0, t1),
                   kick_close = line.gravity_kick(mid, t1);
      for (int i = 0; i < sheets; ++i) {
        v[i] += four_pi_g_rho * (x[i] - q[i]) * kick_open;
        x[i] += v[i] * drift;
        v[i] += four_pi_g_rho * (x[i] - q[i]) * kick_close;
      }
    }
    const double a_end = line.scale_factor(static_cast<double>(TimeLine::ticks));
    const double x_amp = (a_end / a_c) / wave, v_amp = H0 * std::pow(a_end, 1.5) / (a_c * wave);
    std::pair<double, double> e{0.0, 0.0};
    for (int i = 0; i < sheets; ++i) {
      e.first = std::max(e.first, std::fabs(x[i] - exact_x(q[i], a_end)) / x_amp);
      e.second = std::max(e.second, std::fabs(v[i] - exact_v(q[i], a_end)) / v_amp);
    }
    return e;
  };
  expect_rel(line.scale_factor(static_cast<double>(TimeLine::ticks)), 0.4, 1e-14, "the timeline ends at a_end");
  const auto [x_err, v_err] = errors(TimeLine::max_bin - 9);  // 512 steps
  EXPECT_LT(x_err, 3e-5);
  EXPECT_LT(v_err, 3e-5);
  std::printf("Zel'dovich sheets, 512 steps: position error %.2e, velocity error %.2e of the amplitudes\n", x_err,
              v_err);
  // Second order: twice the steps, a quarter of the error.
  const auto [x_fine, v_fine] = errors(TimeLine::max_bin - 10);
  EXPECT_NEAR(x_err / x_fine, 4.0, 0.4);
  EXPECT_NEAR(v_err / v_fine, 4.0, 0.4);
}

TEST(ComovingTimeLine, HalfStepsTelescopeAndBinsFollowTheExpansionRate) {
  const Background b({0.3, 0.7, 0.04, 0.6});
  const IntegrationFactors k(b, 5.0 / 3.0, 0.02, 1.0);
  const ComovingTimeLine line(k);
  // The two half kicks of a step are its whole kick, whatever the bin (bin 0's midpoint is
  // half a tick).
  for (int bin : {0, 10, 40, 56}) {
    const double t0 = bin == 56 ? 0.0 : std::ldexp(3.0, bin), step = std::ldexp(1.0, bin);
    const double whole = line.gravity_kick(t0, t0 + step);
    const double halves = line.gravity_kick(t0, t0 + 0.5 * step) + line.gravity_kick(t0 + 0.5 * step, t0 + step);
    EXPECT_NEAR(halves, whole, 1e-13 * std::fabs(whole) + 1e-300) << "bin " << bin;
  }
  // A physical dt becomes a step in ln a of H(a) dt: the chosen bin's step fits, twice it does not.
  const IntegerTime ti = TimeLine::ticks / 4;
  const double a = line.scale_factor(static_cast<double>(ti));
  const double dt = 1e-4;  // internal time units
  const int bin = line.bin_for(dt, ti, 1.0);
  ASSERT_GE(bin, 0);
  const double hubble = b.hubble(a);
  EXPECT_LE(std::ldexp(line.ln_a_per_tick(), bin), hubble * dt);
  EXPECT_GT(std::ldexp(line.ln_a_per_tick(), bin + 1), hubble * dt);
  // The largest step in ln a caps it.
  EXPECT_LE(std::ldexp(line.ln_a_per_tick(), line.bin_for(1.0, ti, 0.01)), 0.01);
  EXPECT_EQ(line.bin_for(0.0, ti, 0.01), -1);
}

}  // namespace
}  // namespace fountain
