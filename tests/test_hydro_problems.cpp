// Whole runs of the standard hydro problems against their exact solutions, conservation
// and reproducibility. Resolutions are small so the suite stays fast; the error bounds
// are stated (and justified) in docs/validation.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/Engine.hpp"
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

// Exact Sod profile (x relative to the interface, rho column) read from the shipped table.
struct SodExact {
  std::vector<double> x, rho;
  SodExact() {
    std::ifstream in(std::string(FOUNTAIN_SOURCE_DIR) + "/data/hydro_tests/sod_exact_gamma5_3_t0.2.txt");
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ss(line);
      double a, b;
      ss >> a >> b;
      x.push_back(a);
      rho.push_back(b);
    }
  }
  double operator()(double xi) const {
    const auto it = std::lower_bound(x.begin(), x.end(), xi);
    if (it == x.begin()) return rho.front();
    if (it == x.end()) return rho.back();
    const std::size_t k = static_cast<std::size_t>(it - x.begin());
    const double w = (xi - x[k - 1]) / (x[k] - x[k - 1]);
    return rho[k - 1] + w * (rho[k] - rho[k - 1]);
  }
};

double sod_l1(const GasParticles& g) {
  static const SodExact exact;
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double dx = g.x[i].x - 1.0;
    if (std::fabs(dx) >= 0.5) continue;
    sum += std::fabs(g.rho[i] - exact(dx));
    ++n;
  }
  return sum / static_cast<double>(n);
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

double sedov_shock_radius(const GasParticles& g) {
  // Where the radially binned density, outside its peak, falls half way from the peak to the
  // ambient density: the middle of the smeared jump (bins of 1/10 the particle spacing).
  const int nbins = 100;
  const double rmax = 0.5;
  std::vector<double> mass(nbins, 0.0), rho(nbins, 0.0);
  std::vector<int> count(nbins, 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    Vec3 d = g.x[i] - Vec3{0.5, 0.5, 0.5};
    for (int k = 0; k < 3; ++k) d[k] -= std::round(d[k]);
    const int b = static_cast<int>(norm(d) / rmax * nbins);
    if (b >= nbins) continue;
    rho[b] += g.rho[i];
    ++count[b];
  }
  std::vector<double> mean(nbins, 0.0);
  for (int b = 0; b < nbins; ++b) mean[b] = count[b] > 0 ? rho[b] / count[b] : 0.0;
  int peak = 0;
  for (int b = 0; b < nbins; ++b)
    if (mean[b] > mean[peak]) peak = b;
  const double half = 1.0 + 0.5 * (mean[peak] - 1.0);
  int b = peak;
  while (b + 2 < nbins && mean[b + 1] > half) ++b;
  const double w = (mean[b] - half) / (mean[b] - mean[b + 1]);
  return (b + 0.5 + w) * rmax / nbins;
}

TEST(SedovBlast, ShockRadiusAndConservation) {
  const auto ic = ics::sedov_blast(20, 5.0 / 3.0);
  const double t_end = 0.05;
  RunConfig cfg = problem_config(ic, t_end, 5e-4, false, 2);
  // Neighbours' steps within 2x: with 4x the energy error at the blast's start is 1.25e-3.
  cfg.hydro.limiter_bins = 1;
  Engine e(cfg, ic.gas);
  e.initialise();
  e.drift_all();
  const Totals start = e.totals();
  while (!e.finished()) e.step();
  e.drift_all();
  const Totals end = e.totals();
  const double r_exact = 1.15167 * std::pow(1.0 * t_end * t_end / 1.0, 0.2);
  const double r = sedov_shock_radius(e.gas());
  std::printf("Sedov (16000 particles): shock radius %.4f vs %.4f (%.2f%%); energy drift %.2e; steps %lld\n", r,
              r_exact, 100 * (r / r_exact - 1), end.energy() / start.energy() - 1, e.steps());
  EXPECT_NEAR(r / r_exact, 1.0, 0.03);
  EXPECT_LT(std::fabs(end.energy() / start.energy() - 1.0), 1e-3);
  // Momentum: zero initially; pairwise-antisymmetric forces keep it at round-off.
  const double p_scale = std::sqrt(2.0 * start.mass * start.energy());
  EXPECT_LT(norm(end.momentum), 1e-12 * p_scale) << "momentum " << norm(end.momentum);
  EXPECT_DOUBLE_EQ(end.mass, start.mass);
}

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

}  // namespace
}  // namespace fountain
