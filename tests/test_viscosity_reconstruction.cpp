// The viscosity's reconstruction (hydro.viscosity_reconstruction), tested alone: the strain
// rate it reads, the limited approach speed, and the pair force it gives.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "hydro/HydroIact.hpp"

namespace fountain {
namespace {

// A velocity gradient with every entry set (not symmetric) and a uniform drift.
struct LinearFlow {
  double g[3][3] = {{0.7, -1.3, 0.4}, {2.1, -0.5, 0.9}, {-0.8, 1.7, 0.3}};
  Vec3 v0{3.0, -2.0, 1.0};
  Vec3 at(const Vec3& x) const {
    return v0 + Vec3{g[0][0] * x.x + g[0][1] * x.y + g[0][2] * x.z, g[1][0] * x.x + g[1][1] * x.y + g[1][2] * x.z,
                     g[2][0] * x.x + g[2][1] * x.y + g[2][2] * x.z};
  }
  double symmetric(int a, int b) const { return 0.5 * (g[a][b] + g[b][a]); }
};

// The pairs of a particle at the origin with neighbours at `x` moving with `flow`, listed both
// as scalar sums and for the four-lane loop.
struct Neighbourhood {
  hydro::GradientSums one;
  hydro::DensityPairs pairs;
  double h;

  Neighbourhood(const std::vector<Vec3>& x, const std::vector<double>& m, const LinearFlow& flow, double h_) : h(h_) {
    pairs.reset(x.size() + 1);
    const Vec3 vi = flow.at({});
    for (std::size_t k = 0; k < x.size(); ++k) {
      const Vec3 dx = -x[k], dv = vi - flow.at(x[k]);
      const double r2 = dot(dx, dx);
      if (r2 >= h * h) continue;
      hydro::iact_gradient(dx, dv, r2, 1.0 / h, m[k], one);
      pairs.add(dx, dv, r2, m[k]);
    }
    // The particle itself, as the loops list it: it adds nothing.
    hydro::iact_gradient({}, {}, 0.0, 1.0 / h, 1.0, one);
    pairs.add({}, {}, 0.0, 1.0);
  }
};

void expect_strain(const hydro::StrainRate& s, const LinearFlow& flow, double tol, const char* where) {
  const double want[6] = {flow.symmetric(0, 0), flow.symmetric(1, 1), flow.symmetric(2, 2),
                          flow.symmetric(0, 1), flow.symmetric(0, 2), flow.symmetric(1, 2)};
  const double got[6] = {s.diagonal.x, s.diagonal.y, s.diagonal.z, s.shear.x, s.shear.y, s.shear.z};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(got[k], want[k], tol) << where << ", entry " << k;
}

// Any arrangement of neighbours, any masses: the corrected estimate recovers a linear flow's
// strain to round-off, in the scalar and the four-lane forms alike.
TEST(ViscosityReconstruction, StrainRateIsExactForLinearFlows) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(-1.0, 1.0), mass(0.5, 2.0);
  const LinearFlow flow;
  std::vector<Vec3> x;
  std::vector<double> m;
  for (int k = 0; k < 400; ++k) {
    x.push_back({uni(rng), uni(rng), uni(rng)});
    m.push_back(mass(rng));
  }
  Neighbourhood random(x, m, flow, 0.8);
  ASSERT_GT(random.pairs.n, 60u);
  expect_strain(hydro::strain_rate(random.one), flow, 1e-12, "random, scalar");
  expect_strain(hydro::sum_strain_pairs(random.pairs, random.h), flow, 1e-12, "random, lanes");

  // A lattice squeezed five times along x (the planes of a collapsing pancake): the plain SPH
  // divergence is off by tens of percent here; the corrected gradient is not.
  x.clear(), m.clear();
  for (int i = -6; i <= 6; ++i)
    for (int j = -3; j <= 3; ++j)
      for (int k = -3; k <= 3; ++k)
        if (i != 0 || j != 0 || k != 0) x.push_back({0.06 * i, 0.3 * j + 0.01, 0.3 * k - 0.02}), m.push_back(1.0);
  Neighbourhood squeezed(x, m, flow, 0.7);
  expect_strain(hydro::sum_strain_pairs(squeezed.pairs, squeezed.h), flow, 1e-12, "squeezed lattice");
}

// Neighbours all in one plane give no gradient out of it: the strain is zero, and the
// viscosity is the plain one.
TEST(ViscosityReconstruction, CoplanarNeighboursGiveNoStrain) {
  std::vector<Vec3> x;
  std::vector<double> m;
  for (int j = -3; j <= 3; ++j)
    for (int k = -3; k <= 3; ++k)
      if (j != 0 || k != 0) x.push_back({0.0, 0.2 * j, 0.2 * k}), m.push_back(1.0);
  Neighbourhood plane(x, m, LinearFlow{}, 0.7);
  ASSERT_GT(plane.pairs.n, 20u);
  const hydro::StrainRate s = hydro::sum_strain_pairs(plane.pairs, plane.h);
  EXPECT_EQ(s.diagonal, Vec3{});
  EXPECT_EQ(s.shear, Vec3{});
}

TEST(ViscosityReconstruction, LimitedApproach) {
  // Agreeing slopes: the linear part goes, all of it when the slopes are equal.
  EXPECT_EQ(hydro::reconstructed_approach(-2.0, -2.0, -2.0), 0.0);
  EXPECT_NEAR(hydro::reconstructed_approach(-2.0, -1.9, -2.1), -2.0 + 0.5 * (4 * 1.9 * 2.1 / 16.0) * 4.0, 1e-15);
  // Slopes of opposite sign (a jump between them) or a flat side: the pair's own approach.
  EXPECT_EQ(hydro::reconstructed_approach(-2.0, -1.0, 1.0), -2.0);
  EXPECT_EQ(hydro::reconstructed_approach(-2.0, 0.0, -3.0), -2.0);
  // The shock fraction scales the shift by x^4: with x = 1/2, a sixteenth of it.
  EXPECT_NEAR(hydro::reconstructed_approach(-2.0, -2.0, -2.0, {1.0, 2.0}), -2.0 + 2.0 / 16.0, 1e-15);
  EXPECT_EQ(hydro::reconstructed_approach(-2.0, -2.0, -2.0, {0.0, 2.0}), -2.0);
  // Receding pairs are left alone; the result never exceeds the approach nor turns it round.
  EXPECT_EQ(hydro::reconstructed_approach(1.5, 1.0, 1.0), 1.5);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(-3.0, 3.0);
  for (int k = 0; k < 10000; ++k) {
    const double vr = uni(rng), si = uni(rng), sj = uni(rng);
    const double w = hydro::reconstructed_approach(vr, si, sj);
    EXPECT_EQ(w, hydro::reconstructed_approach(vr, sj, si));  // symmetric in i and j
    if (vr < 0.0) {
      EXPECT_GE(w, vr);
      EXPECT_LE(w, 0.0);
    }
  }
}

// One entropy: the whole reconstruction; a pressure jump that matters against the approach's
// ram pressure: almost none; a cold pair heated slightly (its pressures far below the ram's): nearly all.
double shock_weight(double ki, double kj, double pi, double pj, double rho_ij, double vr, double r2) {
  const hydro::ShockFraction f = hydro::shock_fraction(ki, kj, pi, pj, rho_ij, vr, r2);
  const double x = f.num / f.den;
  return x * x * x * x;
}

TEST(ViscosityReconstruction, ShockWeight) {
  const double r2 = 0.04, vr = -0.2;  // approach 1 at density 1: ram pressure 1
  EXPECT_EQ(shock_weight(2.0, 2.0, 5.0, 7.0, 1.0, vr, r2), 1.0);
  EXPECT_LT(shock_weight(100.0, 1.0, 10.0, 0.1, 1.0, vr, r2), 1e-3);
  EXPECT_GT(shock_weight(1.0, 1.5, 1e-4, 1.5e-4, 1.0, vr, r2), 0.999);
  EXPECT_EQ(shock_weight(1.0, 3.0, 1.0, 3.0, 1.0, vr, r2), shock_weight(3.0, 1.0, 3.0, 1.0, 1.0, vr, r2));
}

hydro::ForceState state(const Vec3& v, double u, const hydro::StrainRate& strain, const HydroParams& p) {
  return hydro::make_force_state(v, 1.0, 1.0, u, 0.5, -1.0, {}, p, strain);
}

// In a linear flow the reconstruction removes the viscosity: the pair force is the pressure
// force alone (alpha_v = 0), while without it the same approaching pair is braked.
TEST(ViscosityReconstruction, LinearFlowFeelsNoViscosity) {
  const LinearFlow flow;
  const hydro::StrainRate strain{{flow.symmetric(0, 0), flow.symmetric(1, 1), flow.symmetric(2, 2)},
                                 {flow.symmetric(0, 1), flow.symmetric(0, 2), flow.symmetric(1, 2)}};
  HydroParams p, inviscid, plain;
  p.viscosity_reconstruction = true;
  inviscid.viscosity_alpha = 0.0;
  const Vec3 xi{0.01, 0.1, -0.01}, xj{-0.01, -0.1, 0.01};  // approaching: dx^T G dx < 0
  const Vec3 dx = xi - xj;
  ASSERT_LT(dot(flow.at(xi) - flow.at(xj), dx), 0.0);
  hydro::ForceSums rec, none, braked;
  hydro::iact_force(state(flow.at(xi), 0.1, strain, p), state(flow.at(xj), 0.1, strain, p), dx, dot(dx, dx), p, rec);
  hydro::iact_force(state(flow.at(xi), 0.1, {}, inviscid), state(flow.at(xj), 0.1, {}, inviscid), dx, dot(dx, dx),
                    inviscid, none);
  hydro::iact_force(state(flow.at(xi), 0.1, {}, plain), state(flow.at(xj), 0.1, {}, plain), dx, dot(dx, dx), plain,
                    braked);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(rec.a[d], none.a[d], 1e-12 * norm(none.a));
  EXPECT_NEAR(rec.du_dt, none.du_dt, 1e-12 * std::fabs(none.du_dt));
  EXPECT_GT(norm(braked.a - none.a), 0.1 * norm(none.a));  // the plain viscosity is not small here
}

// Where the two sides' slopes disagree in sign (a shock front between them) the whole
// viscosity acts; the pair force stays antisymmetric and the heating equals the work.
TEST(ViscosityReconstruction, JumpKeepsTheWholeViscosity) {
  HydroParams p, plain;
  p.viscosity_reconstruction = true;
  const hydro::StrainRate squeezing{{-5.0, 0, 0}, {}}, stretching{{3.0, 0, 0}, {}};
  const Vec3 dx{0.2, 0.01, 0.0};
  const Vec3 vi{-1.0, 0, 0}, vj{1.0, 0, 0};
  hydro::ForceSums rec_i, rec_j, plain_i;
  const auto si = state(vi, 0.1, squeezing, p), sj = state(vj, 0.2, stretching, p);
  hydro::iact_force(si, sj, dx, dot(dx, dx), p, rec_i);
  hydro::iact_force(sj, si, -dx, dot(dx, dx), p, rec_j);
  hydro::iact_force(state(vi, 0.1, {}, plain), state(vj, 0.2, {}, plain), dx, dot(dx, dx), plain, plain_i);
  EXPECT_EQ(rec_i.a, plain_i.a);
  EXPECT_EQ(rec_i.a, -rec_j.a);  // equal masses: equal and opposite accelerations
}

// The four-lane force loop with reconstruction, plain and comoving, against the one-pair form
// (comoving with a zero Hubble flow is the plain force).
TEST(ViscosityReconstruction, LanesMatchOnePairForm) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  HydroParams p;
  p.viscosity_reconstruction = true;
  auto strain = [&] { return hydro::StrainRate{{uni(rng), uni(rng), uni(rng)}, {uni(rng), uni(rng), uni(rng)}}; };
  auto make = [&] {
    return hydro::make_force_state({uni(rng), uni(rng), uni(rng)}, 1.0 + 0.5 * uni(rng), 1.0 + 0.9 * uni(rng),
                                   2.0 + uni(rng), 0.5 + 0.2 * uni(rng), uni(rng), {uni(rng), uni(rng), uni(rng)}, p,
                                   strain());
  };
  const hydro::ForceState fi = make();
  hydro::ForceSums one;
  hydro::ForcePairs q;
  q.reset(600, true);
  int pairs = 0;
  for (int k = 0; k < 600; ++k) {
    const hydro::ForceState fj = make();
    const Vec3 dx = Vec3{uni(rng), uni(rng), uni(rng)} * 0.7;
    const double r2 = dot(dx, dx);
    if (r2 >= fi.h * fi.h && r2 >= fj.h * fj.h) continue;
    ++pairs;
    hydro::iact_force(fi, fj, dx, r2, p, one);
    q.add(dx, fi.v - fj.v, r2, fj);
    q.add_strain(fj.entropy, fj.strain);
  }
  ASSERT_GT(pairs, 100);
  ASSERT_NE(pairs % hydro::kLanes, 0);
  const hydro::ForceSums s = hydro::sum_force_pairs<true, false, true>(fi, q, p);
  const hydro::ForceSums comoving = hydro::sum_force_pairs<true, true, true>(fi, q, p, 0.0);
  const hydro::ForceSums without = hydro::sum_force_pairs<true, false, false>(fi, q, p);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(s.a[d], one.a[d], 1e-12 * norm(one.a));
  EXPECT_NEAR(s.du_dt, one.du_dt, 1e-12 * std::fabs(one.du_dt));
  EXPECT_EQ(comoving.a, s.a);
  EXPECT_NEAR(comoving.du_dt, s.du_dt, 1e-12 * std::fabs(s.du_dt));  // its energy terms are grouped otherwise
  EXPECT_NE(without.du_dt, s.du_dt);  // some pair's viscosity did change
}

}  // namespace
}  // namespace fountain
