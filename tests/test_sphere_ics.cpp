// Tests of the rotating collapsing sphere initial conditions (Navarro & White 1993 set-up,
// docs/physics.md §8.1) and of writing them, with dark matter, as a GADGET HDF5 file.
#include <gtest/gtest.h>

#include "TempDirTest.hpp"
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "core/Error.hpp"
#include "hydro/Kernel.hpp"
#include "ics/RotatingSphere.hpp"
#include "io/Hdf5File.hpp"
#include "io/InitialConditions.hpp"

namespace fs = std::filesystem;
using fountain::InputError;
using fountain::Vec3;
using fountain::ics::RotatingSphereIC;
using fountain::ics::RotatingSphereParams;

namespace {

constexpr int kN = 4000;  // particles per species, as in the paper's R01-R05 runs

// The paper's sphere at N = 4000, built once for all tests.
const RotatingSphereIC& paper_sphere() {
  static const RotatingSphereIC ic = [] {
    RotatingSphereParams p;
    p.particles_per_species = kN;
    return fountain::ics::rotating_sphere(p);
  }();
  return ic;
}

// Every particle of both species, gas first.
struct AllParticles {
  std::vector<Vec3> x, v;
  std::vector<double> m;
};

AllParticles all_particles(const RotatingSphereIC& ic) {
  AllParticles a;
  for (std::size_t i = 0; i < ic.gas.size(); ++i) {
    a.x.push_back(ic.gas.x[i]);
    a.v.push_back(ic.gas.v_full[i]);
    a.m.push_back(ic.gas.mass[i]);
  }
  for (std::size_t i = 0; i < ic.dm.size(); ++i) {
    a.x.push_back(ic.dm.x[i]);
    a.v.push_back(ic.dm.v_full[i]);
    a.m.push_back(ic.dm.mass[i]);
  }
  return a;
}

double sum(const std::vector<double>& values) {
  double s = 0.0;
  for (double v : values) s += v;
  return s;
}

// Plain serial direct sum, unsoftened: independent of the generator's own routine.
double potential_energy(const AllParticles& a, double G) {
  double w = 0.0;
  for (std::size_t i = 0; i < a.x.size(); ++i) {
    double row = 0.0;
    for (std::size_t j = i + 1; j < a.x.size(); ++j) row += a.m[j] / norm(a.x[j] - a.x[i]);
    w -= G * a.m[i] * row;
  }
  return w;
}

// Spin parameter and thermal fraction recomputed from the particles alone.
struct Measured {
  double spin = 0.0, thermal_fraction = 0.0, W = 0.0;
};

Measured measure(const RotatingSphereIC& ic, double G) {
  const AllParticles a = all_particles(ic);
  const double M = sum(a.m);
  Vec3 com{}, vcom{};
  for (std::size_t i = 0; i < a.x.size(); ++i) com += a.m[i] * a.x[i], vcom += a.m[i] * a.v[i];
  com *= 1.0 / M;
  vcom *= 1.0 / M;
  double J = 0.0, K = 0.0;
  for (std::size_t i = 0; i < a.x.size(); ++i) {
    const Vec3 dx = a.x[i] - com, dv = a.v[i] - vcom;
    J += a.m[i] * (dx.x * dv.y - dx.y * dv.x);
    K += 0.5 * a.m[i] * dot(dv, dv);
  }
  double U = 0.0, m_gas = 0.0;
  for (std::size_t i = 0; i < ic.gas.size(); ++i) U += ic.gas.mass[i] * ic.gas.u_full[i], m_gas += ic.gas.mass[i];
  Measured out;
  out.W = potential_energy(a, G);
  const double E = K + out.W + U;
  out.spin = std::abs(J) * std::sqrt(std::abs(E)) / (G * std::pow(M, 2.5));
  out.thermal_fraction = (U / m_gas) / (std::abs(out.W) / M);
  return out;
}

// Radius the stretch came from: r_old = R (r/R)^(2/3).
double lattice_radius(const Vec3& x, double R) { return R * std::cbrt(std::pow(norm(x) / R, 2.0)); }

// Mass in log-spaced radial bins between r_lo and r_hi, over the expected share of the
// rho = M/(2 pi R^2 r) profile, M (r1^2 - r0^2)/R^2. With `smooth` > 0 each particle is spread
// uniformly in volume over [r_old - smooth/2, r_old + smooth/2] of its pre-stretch radius:
// the lattice then counts as the smooth medium it stands for, instead of as a few discrete
// shells (a thin radial bin of a cubic lattice holds one or two of its spherical shells).
std::vector<double> profile_ratios(const std::vector<Vec3>& x, const std::vector<double>& m, double expected_mass,
                                   double R, int bins, double r_lo, double r_hi, double smooth) {
  std::vector<double> ratio(bins);
  for (int b = 0; b < bins; ++b) {
    const double r0 = r_lo * std::pow(r_hi / r_lo, static_cast<double>(b) / bins);
    const double r1 = r_lo * std::pow(r_hi / r_lo, static_cast<double>(b + 1) / bins);
    const double o0 = R * std::pow(r0 / R, 2.0 / 3.0), o1 = R * std::pow(r1 / R, 2.0 / 3.0);
    double mass = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double r = norm(x[i]);
      if (smooth <= 0.0) {
        if (r >= r0 && r < r1) mass += m[i];
        continue;
      }
      const double s = lattice_radius(x[i], R);
      const double in = std::max(0.0, s - 0.5 * smooth), out = s + 0.5 * smooth;
      const double lo = std::clamp(o0, in, out), hi = std::clamp(o1, in, out);
      mass += m[i] * (hi * hi * hi - lo * lo * lo) / (out * out * out - in * in * in);
    }
    ratio[b] = mass / (expected_mass * (r1 * r1 - r0 * r0) / (R * R));
  }
  return ratio;
}

double max_deviation(const std::vector<double>& ratios) {
  double d = 0.0;
  for (double r : ratios) d = std::max(d, std::abs(r - 1.0));
  return d;
}

// Least-squares slope of log M(<r) against log r over the particles with r in [r_lo, r_hi]
// (M(<r) taken half-way through each particle's own mass): 2 for rho ~ 1/r.
double cumulative_slope(std::vector<Vec3> x, double m, double r_lo, double r_hi) {
  std::sort(x.begin(), x.end(), [](const Vec3& a, const Vec3& b) { return norm(a) < norm(b); });
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double r = norm(x[i]);
    if (r < r_lo || r > r_hi) continue;
    const double lx = std::log(r), ly = std::log((static_cast<double>(i) + 0.5) * m);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, n += 1;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// Kernel density estimates, as SPH measures density: each particle's h encloses its 48
// nearest neighbours (itself included) and rho_i = sum_j m_j W(r_ij, h_i) with the code's
// cubic spline. Brute force.
std::vector<double> kernel_densities(const std::vector<Vec3>& x, const std::vector<double>& m) {
  const std::size_t n = x.size();
  std::vector<double> rho(n), d2(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const Vec3 d = x[i] - x[j];
      d2[j] = dot(d, d);
    }
    std::vector<double> sorted(d2);
    std::nth_element(sorted.begin(), sorted.begin() + 47, sorted.end());
    const double h = std::sqrt(sorted[47]) * 1.0000001, h_inv = 1.0 / h;
    double sum = 0.0;
    for (std::size_t j = 0; j < n; ++j)
      if (d2[j] < h * h) sum += m[j] * fountain::kernel::value(std::sqrt(d2[j]), h_inv);
    rho[i] = sum;
  }
  return rho;
}

// Mean over the particles of each of `bins` log bins in [r_lo, r_hi] of rho_i / rho(r_i) for
// rho(r) = mass / (2 pi R^2 r), the 1/r profile holding `mass` within R.
std::vector<double> kernel_profile_ratios(const std::vector<Vec3>& x, const std::vector<double>& rho, double mass,
                                          double R, int bins, double r_lo, double r_hi) {
  std::vector<double> sum(bins, 0.0), count(bins, 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double r = norm(x[i]);
    if (r < r_lo || r >= r_hi) continue;
    const int b = std::min(bins - 1, static_cast<int>(bins * std::log(r / r_lo) / std::log(r_hi / r_lo)));
    sum[b] += rho[i] / (mass / (2.0 * std::numbers::pi * R * R * r));
    count[b] += 1.0;
  }
  // A bin holding no particle has no estimate (NaN).
  for (int b = 0; b < bins; ++b) sum[b] = count[b] > 0.0 ? sum[b] / count[b] : std::nan("");
  return sum;
}

class SphereIcsFile : public fountain::testing::TempDirTest {};

}  // namespace

TEST(SphereIcs, ParticleCountsCloseToTarget) {
  for (int n : {2000, 4000, 8000}) {
    RotatingSphereParams p;
    p.particles_per_species = n;
    p.smoothing_neighbours = 0.0;
    const RotatingSphereIC ic = fountain::ics::rotating_sphere(p);
    EXPECT_NEAR(static_cast<double>(ic.gas.size()), n, 0.02 * n) << "N = " << n;
    EXPECT_NEAR(static_cast<double>(ic.dm.size()), n, 0.02 * n) << "N = " << n;
    EXPECT_NEAR(static_cast<double>(ic.gas.size() + ic.dm.size()), 2.0 * n, 0.01 * n) << "N = " << n;
    RecordProperty("counts_" + std::to_string(n), std::to_string(ic.gas.size()) + " gas + " +
                                                      std::to_string(ic.dm.size()) + " dm");
  }
}

TEST(SphereIcs, MassesAndGasFractionExact) {
  const RotatingSphereIC& ic = paper_sphere();
  const RotatingSphereParams p;
  const double m_gas = sum(ic.gas.mass), m_dm = sum(ic.dm.mass);
  EXPECT_NEAR((m_gas + m_dm) / p.total_mass, 1.0, 1e-12);
  EXPECT_NEAR(m_gas / (m_gas + m_dm), p.gas_fraction, 1e-12);
  for (double m : ic.gas.mass) ASSERT_EQ(m, ic.gas.mass[0]);
  for (double m : ic.dm.mass) ASSERT_EQ(m, ic.dm.mass[0]);
}

TEST(SphereIcs, IdsUniqueAcrossSpecies) {
  const RotatingSphereIC& ic = paper_sphere();
  std::vector<std::uint64_t> ids(ic.gas.id);
  ids.insert(ids.end(), ic.dm.id.begin(), ic.dm.id.end());
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(std::adjacent_find(ids.begin(), ids.end()), ids.end());
  EXPECT_GE(ids.front(), 1u);
}

TEST(SphereIcs, CentreOfMassAtOriginAtRest) {
  const RotatingSphereIC& ic = paper_sphere();
  const RotatingSphereParams p;
  const AllParticles a = all_particles(ic);
  Vec3 com{}, p_tot{};
  for (std::size_t i = 0; i < a.x.size(); ++i) com += a.m[i] * a.x[i], p_tot += a.m[i] * a.v[i];
  const double M = sum(a.m);
  EXPECT_LT(norm(com * (1.0 / M)), 1e-13 * p.radius);
  EXPECT_LT(norm(p_tot * (1.0 / M)), 1e-13 * ic.omega * p.radius);
  // Inside the sphere, solid-body rotation about z, uniform u.
  for (std::size_t i = 0; i < a.x.size(); ++i) {
    ASSERT_LT(norm(a.x[i]), p.radius);
    ASSERT_EQ(a.v[i].z, 0.0);
    ASSERT_NEAR(a.v[i].x, -ic.omega * a.x[i].y, 1e-12 * ic.omega * p.radius);
    ASSERT_NEAR(a.v[i].y, ic.omega * a.x[i].x, 1e-12 * ic.omega * p.radius);
  }
  for (std::size_t i = 0; i < ic.gas.size(); ++i) {
    ASSERT_EQ(ic.gas.u_full[i], ic.u);
    ASSERT_EQ(ic.gas.u[i], ic.u);
    ASSERT_EQ(ic.gas.v[i], ic.gas.v_full[i]);
    ASSERT_GT(ic.gas.h[i], 0.0);
  }
}

// The stretch is exactly r_new = R (r_old/R)^(3/2) of a cubic lattice: mapped back, the DM
// sits at r_old^2 = d^2 (i^2 + j^2 + k^2) and the gas (shifted by d/2) at d^2 (odd^2 sum)/4.
TEST(SphereIcs, StretchMapsBackToTheLattices) {
  const RotatingSphereIC& ic = paper_sphere();
  const RotatingSphereParams p;
  const double d = ic.lattice_spacing;
  for (const Vec3& x : ic.dm.x) {
    const double q = std::pow(lattice_radius(x, p.radius) / d, 2);
    ASSERT_NEAR(q, std::round(q), 1e-8 * std::max(1.0, q));
  }
  for (const Vec3& x : ic.gas.x) {
    const double q = 4.0 * std::pow(lattice_radius(x, p.radius) / d, 2);  // a sum of three odd squares: 3 mod 8
    ASSERT_NEAR(q, std::round(q), 1e-8 * q);
    ASSERT_EQ(static_cast<long>(std::round(q)) % 8, 3);
  }
}

TEST(SphereIcs, DensityProfileIsOneOverR) {
  const RotatingSphereIC& ic = paper_sphere();
  const RotatingSphereParams p;
  const double R = p.radius, M = p.total_mass, d = ic.lattice_spacing;
  const AllParticles a = all_particles(ic);
  const int bins = 8;
  // Each particle spread over two lattice spacings of its pre-stretch radius.
  const double dev_all = max_deviation(profile_ratios(a.x, a.m, M, R, bins, 0.15 * R, 0.85 * R, 2.0 * d));
  const double dev_gas =
      max_deviation(profile_ratios(ic.gas.x, ic.gas.mass, p.gas_fraction * M, R, bins, 0.15 * R, 0.85 * R, 2.0 * d));
  EXPECT_LT(dev_all, 0.05);
  EXPECT_LT(dev_gas, 0.05);
  // Raw particle counts in the same thin bins (each bin is < 1 lattice spacing thick before
  // the stretch, so it holds one or two lattice shells): recorded, not checked.
  const double raw_all = max_deviation(profile_ratios(a.x, a.m, M, R, bins, 0.15 * R, 0.85 * R, 0.0));
  const double raw_gas =
      max_deviation(profile_ratios(ic.gas.x, ic.gas.mass, p.gas_fraction * M, R, bins, 0.15 * R, 0.85 * R, 0.0));
  RecordProperty("smoothed_max_deviation_all", std::to_string(dev_all));
  RecordProperty("smoothed_max_deviation_gas", std::to_string(dev_gas));
  RecordProperty("raw_max_deviation_all", std::to_string(raw_all));
  RecordProperty("raw_max_deviation_gas", std::to_string(raw_gas));
  std::printf("density profile, 8 log bins 0.15-0.85 R: max deviation smoothed %.4f (all) %.4f (gas); raw %.4f (all) "
              "%.4f (gas)\n",
              dev_all, dev_gas, raw_all, raw_gas);
  // The raw particles: M(<r) ~ r^2 (slope of log M(<r) against log r over 0.15-0.85 R).
  const double slope_dm = cumulative_slope(ic.dm.x, ic.dm.mass[0], 0.15 * R, 0.85 * R);
  const double slope_gas = cumulative_slope(ic.gas.x, ic.gas.mass[0], 0.15 * R, 0.85 * R);
  std::printf("cumulative mass slope: %.4f (dm) %.4f (gas)\n", slope_dm, slope_gas);
  EXPECT_NEAR(slope_dm, 2.0, 0.02);
  EXPECT_NEAR(slope_gas, 2.0, 0.02);
  // Closed form for this profile: W = -(2/3) G M^2 / R.
  EXPECT_NEAR(ic.potential_energy / (-2.0 / 3.0 * p.G * M * M / R), 1.0, 0.02);
}

// The density as SPH sees it: kernel estimates over 48 neighbours, all matter together and
// the gas alone, averaged in 8 log bins over 0.15-0.85 R (the lattice's shells, which make
// raw counts in thin bins jump, are what any smoothing over neighbours averages out).
class SphereIcsSizes : public ::testing::TestWithParam<int> {};

TEST_P(SphereIcsSizes, KernelDensityProfileIsOneOverR) {
  RotatingSphereParams p;
  p.particles_per_species = GetParam();
  const RotatingSphereIC ic = fountain::ics::rotating_sphere(p);
  const double R = p.radius, M = p.total_mass;
  const AllParticles a = all_particles(ic);
  const int bins = 8;
  const std::vector<double> all = kernel_profile_ratios(a.x, kernel_densities(a.x, a.m), M, R, bins, 0.15 * R, 0.85 * R);
  const std::vector<double> gas = kernel_profile_ratios(ic.gas.x, kernel_densities(ic.gas.x, ic.gas.mass),
                                                        p.gas_fraction * M, R, bins, 0.15 * R, 0.85 * R);
  std::printf("N = %d per species: kernel density / (M / 2 pi R^2 r), 8 log bins 0.15-0.85 R:\n  all:", GetParam());
  for (double v : all) std::printf(" %.4f", v);
  std::printf("\n  gas:");
  for (double v : gas) std::printf(" %.4f", v);
  std::printf("\n");
  // At 2000 per species the gas lattice leaves the innermost bin (0.15-0.19 R) empty: a bin
  // without particles is not a density error, but no more than one may be empty.
  int empty = 0;
  for (int b = 0; b < bins; ++b) {
    EXPECT_NEAR(all[b], 1.0, 0.05) << "all matter, bin " << b;
    if (std::isnan(gas[b])) {
      ++empty;
      continue;
    }
    EXPECT_NEAR(gas[b], 1.0, 0.05) << "gas, bin " << b;
  }
  EXPECT_LE(empty, 1);
}

// 8000 per species (4 s here, too slow under the sanitizers) gives 0.988-0.998 (all) and
// 0.997-0.999 (gas): docs/validation.md.
INSTANTIATE_TEST_SUITE_P(SphereIcs, SphereIcsSizes, ::testing::Values(2000, 4000));

TEST(SphereIcs, SpinAndThermalFractionFromParticles) {
  const RotatingSphereIC& ic = paper_sphere();
  const RotatingSphereParams p;
  const Measured m = measure(ic, p.G);
  std::printf("spin %.6f thermal fraction %.6f omega %.6g u %.6g W %.6g\n", m.spin, m.thermal_fraction, ic.omega, ic.u,
              m.W);
  EXPECT_NEAR(m.spin / p.spin, 1.0, 0.02);
  EXPECT_NEAR(m.thermal_fraction / p.thermal_fraction, 1.0, 0.02);
  // And (tighter) the generator's own bookkeeping agrees with the independent sums.
  EXPECT_NEAR(m.spin / p.spin, 1.0, 1e-6);
  EXPECT_NEAR(ic.potential_energy / m.W, 1.0, 1e-6);
  // Closed forms (docs/physics.md §8.1): |W|/M = 28 673 (km/s)^2, u = 1434 (km/s)^2,
  // omega = 0.778 km/s per kpc/h; the lattice's I_z differs from M R^2/3 by ~1 %.
  EXPECT_NEAR(ic.u / 1434.0, 1.0, 0.02);
  EXPECT_NEAR(ic.omega / 778.0, 1.0, 0.03);
}

TEST(SphereIcs, JitteredLatticeKeepsCentreAndSpin) {
  RotatingSphereParams p;
  p.particles_per_species = 1000;
  p.jitter = 0.3;
  p.spin = 0.05;
  const RotatingSphereIC ic = fountain::ics::rotating_sphere(p);
  const AllParticles a = all_particles(ic);
  Vec3 com{};
  for (std::size_t i = 0; i < a.x.size(); ++i) com += a.m[i] * a.x[i];
  EXPECT_LT(norm(com * (1.0 / sum(a.m))), 1e-13 * p.radius);
  const Measured m = measure(ic, p.G);
  EXPECT_NEAR(m.spin / p.spin, 1.0, 1e-5);
  EXPECT_NEAR(m.thermal_fraction / p.thermal_fraction, 1.0, 1e-5);
  // Deterministic: the same seed gives the same particles.
  const RotatingSphereIC again = fountain::ics::rotating_sphere(p);
  EXPECT_EQ(again.gas.x, ic.gas.x);
  EXPECT_EQ(again.dm.x, ic.dm.x);
}

TEST(SphereIcs, RejectsNonsense) {
  RotatingSphereParams p;
  p.particles_per_species = 200;
  auto bad = [](RotatingSphereParams q) { EXPECT_THROW(fountain::ics::rotating_sphere(q), InputError); };
  auto q = p;
  q.gas_fraction = 0.0;
  bad(q);
  q = p;
  q.radius = -1.0;
  bad(q);
  q = p;
  q.thermal_fraction = 0.0;
  bad(q);
  q = p;
  q.particles_per_species = 2;
  bad(q);
  q = p;
  q.spin = 10.0;  // no bound solid-body rotation has this spin
  bad(q);
}

TEST_F(SphereIcsFile, WriteReadRoundTripWithDarkMatter) {
  RotatingSphereParams p;
  p.particles_per_species = 500;
  const RotatingSphereIC ic = fountain::ics::rotating_sphere(p);
  const std::string path = file("sphere.hdf5");
  const double side = 2.0 * p.radius;
  fountain::io::write_initial_conditions(path, ic.gas, ic.dm, {side, side, side}, false);

  // The project's reader takes both species back.
  const fountain::io::InitialConditions back = fountain::io::read_initial_conditions(path);
  EXPECT_EQ(back.dm.id, ic.dm.id);
  EXPECT_EQ(back.dm.x, ic.dm.x);
  EXPECT_EQ(back.dm.v_full, ic.dm.v_full);
  EXPECT_EQ(back.dm.mass, ic.dm.mass);
  ASSERT_EQ(back.gas.size(), ic.gas.size());
  EXPECT_EQ(back.gas.id, ic.gas.id);
  EXPECT_EQ(back.gas.x, ic.gas.x);
  EXPECT_EQ(back.gas.v_full, ic.gas.v_full);
  EXPECT_EQ(back.gas.mass, ic.gas.mass);
  EXPECT_EQ(back.gas.u_full, ic.gas.u_full);
  EXPECT_EQ(back.gas.h, ic.gas.h);
  EXPECT_TRUE(back.has_smoothing_length);

  // The dark matter and the header, through the HDF5 helpers.
  const fountain::io::hdf5::File f(path, fountain::io::hdf5::File::Mode::read);
  const std::uint64_t n_gas = ic.gas.size(), n_dm = ic.dm.size();
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_ThisFile"), (std::vector<std::uint64_t>{n_gas, n_dm, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_Total"), (std::vector<std::uint64_t>{n_gas, n_dm, 0, 0, 0, 0}));
  EXPECT_EQ(f.read_attribute_uint64("/Header", "NumPart_Total_HighWord"), (std::vector<std::uint64_t>(6, 0)));
  const std::vector<double> table = f.read_attribute_doubles("/Header", "MassTable");
  ASSERT_EQ(table.size(), 6u);
  EXPECT_EQ(table[0], ic.gas.mass[0]);
  EXPECT_EQ(table[1], ic.dm.mass[0]);
  EXPECT_EQ(f.read_attribute_int64("/Header", "Periodic"), (std::vector<std::int64_t>{0}));
  for (const char* name : {"Coordinates", "Velocities", "ParticleIDs", "Masses"}) {
    const auto info = f.dataset_info(std::string("/PartType1/") + name);
    ASSERT_FALSE(info.dims.empty()) << name;
    EXPECT_EQ(info.dims[0], n_dm) << name;
  }
  EXPECT_EQ(f.dataset_info("/PartType1/Coordinates").dims, (std::vector<std::uint64_t>{n_dm, 3}));
  EXPECT_EQ(f.read_vec3("/PartType1/Coordinates"), ic.dm.x);
  EXPECT_EQ(f.read_vec3("/PartType1/Velocities"), ic.dm.v_full);
  EXPECT_EQ(f.read_uint64("/PartType1/ParticleIDs"), ic.dm.id);
  EXPECT_EQ(f.read_doubles("/PartType1/Masses"), ic.dm.mass);
}

TEST_F(SphereIcsFile, WriterRefusesIdsSharedBetweenSpecies) {
  RotatingSphereParams p;
  p.particles_per_species = 100;
  RotatingSphereIC ic = fountain::ics::rotating_sphere(p);
  ic.dm.id[3] = ic.gas.id[7];
  const std::string path = file("dup.hdf5");
  EXPECT_THROW(fountain::io::write_initial_conditions(path, ic.gas, ic.dm, {1, 1, 1}, false), InputError);
  EXPECT_FALSE(fs::exists(path));
}
