// Cosmological initial conditions against known values: the noise generator, Eisenstein & Hu's fit, sigma_8, 2LPT's two-wave solution and the loaded power spectrum.
#include <gtest/gtest.h>

#include <fftw3.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <complex>
#include <numbers>
#include <vector>

#include "cosmology/PowerSpectrum.hpp"
#include "cosmology/TransferFunction.hpp"
#include "ics/CosmologicalBox.hpp"
#include "ics/LagrangianPerturbation.hpp"
#include "ics/WhiteNoise.hpp"

namespace fountain {
namespace {

// Within the digits the reference gives: relative 1e-5, or a unit of its last digit (a value
// quoted to five digits may have been rounded from its own inputs' rounded values).
void expect_value(double got, double reference, double last_digit, const char* what) {
  EXPECT_LE(std::fabs(got - reference), std::max(1e-5 * std::fabs(reference), last_digit))
      << what << ": " << got << " vs " << reference;
}

TEST(CosmologicalIcs, WhiteNoiseGivesTheReferenceValuesAndUnitMoments) {
  const double reference[] = {1.2201955, 1.1822754, -0.3500740, -1.6427605};
  for (int n = 0; n < 4; ++n) expect_value(ics::white_noise(1, 5, static_cast<std::uint64_t>(n)), reference[n], 1e-7, "noise");
  const int level = 6;
  const std::uint64_t cells = std::uint64_t{1} << (3 * level);
  double sum = 0.0, sum2 = 0.0;
  for (std::uint64_t c = 0; c < cells; ++c) {
    const double w = ics::white_noise(7, level, c);
    sum += w;
    sum2 += w * w;
  }
  const double mean = sum / cells, variance = sum2 / cells - mean * mean;
  const double scale = 1.0 / std::sqrt(static_cast<double>(cells));
  EXPECT_LE(std::fabs(mean), 4.0 * scale) << mean;
  EXPECT_LE(std::fabs(variance - 1.0), 5.0 * scale) << variance;
  // Another seed or level is another field.
  EXPECT_NE(ics::white_noise(1, 5, 0), ics::white_noise(2, 5, 0));
  EXPECT_NE(ics::white_noise(1, 5, 0), ics::white_noise(1, 6, 0));
}

TEST(CosmologicalIcs, EisensteinHuMatchesTheReferenceValues) {
  const cosmology::CosmologyParams c{0.3, 0.7, 0.03, 0.6};
  const cosmology::EisensteinHu full(c);
  const auto& s = full.scales();
  expect_value(s.one_plus_z_eq, 2590.845, 1e-3, "1+z_eq");
  expect_value(s.k_eq, 0.007892, 1e-6, "k_eq");
  expect_value(s.z_d, 981.963, 1e-3, "z_d");
  expect_value(s.sound_horizon, 175.5058, 1e-4, "s");
  expect_value(s.k_silk, 0.056705, 1e-6, "k_silk");
  expect_value(s.alpha_c, 0.860053, 1e-6, "alpha_c");
  expect_value(s.beta_c, 1.106351, 1e-6, "beta_c");
  expect_value(s.alpha_b, 0.612542, 1e-6, "alpha_b");
  expect_value(s.beta_b, 6.507056, 1e-6, "beta_b");
  expect_value(s.beta_node, 3.194003, 1e-6, "beta_node");
  expect_value(s.alpha_gamma, 0.877372, 1e-6, "alpha_G");
  expect_value(s.sound_horizon_no_wiggle, 173.7382, 1e-4, "s_nw");
  const cosmology::EisensteinHu no_wiggle(c, cosmology::TransferKind::no_wiggle);
  const cosmology::EisensteinHu zero_baryon(c, cosmology::TransferKind::zero_baryon);
  const double k[] = {0.01, 0.1, 1.0, 10.0};
  const double t_full[] = {0.747053, 0.122221, 0.004239, 8.02e-5}, t_full_digit[] = {1e-6, 1e-6, 1e-6, 1e-7};
  const double t_nw[] = {0.751355, 0.124217, 0.004225, 7.99e-5};
  const double t_zb[] = {0.752487, 0.144773, 0.005232, 1.01e-4}, t_zb_digit[] = {1e-6, 1e-6, 1e-6, 1e-6};
  for (int i = 0; i < 4; ++i) {
    expect_value(full(k[i]), t_full[i], t_full_digit[i], "T_full");
    expect_value(no_wiggle(k[i]), t_nw[i], t_full_digit[i], "T_nw");
    expect_value(zero_baryon(k[i]), t_zb[i], t_zb_digit[i], "T_zero_baryon");
  }
  // The baryon wiggles stay within [0.982, 1.021] of the no-wiggle form (to the reference's
  // three decimals).
  for (double lk = -3.0; lk <= 1.0; lk += 0.01) {
    const double ratio = std::round(1000.0 * full(std::pow(10.0, lk)) / no_wiggle(std::pow(10.0, lk))) / 1000.0;
    EXPECT_GE(ratio, 0.982) << lk;
    EXPECT_LE(ratio, 1.021) << lk;
  }
}

TEST(CosmologicalIcs, Sigma8NormalisationGivesTheReferenceSpectrum) {
  const cosmology::CosmologyParams c{0.3, 0.7, 0.03, 0.6};
  const cosmology::LinearPowerSpectrum p(cosmology::EisensteinHu(c), 1.0, 0.9);
  expect_value(p.amplitude(), 4.649349e6, 1.0, "A");
  expect_value(p(0.01), 2.5948e4, 1.0, "P(0.01)");
  expect_value(p(0.1), 6945.2, 0.1, "P(0.1)");
  expect_value(p(1.0), 83.53, 0.01, "P(1)");
  expect_value(p.sigma(8.0), 0.9, 1e-9, "sigma_8");
  expect_value(p.sigma(1.0), 2.7227, 1e-4, "sigma(1 Mpc/h)");
}

// delta = eps (cos k0 x + cos k0 y): psi1 = -(eps / k0) (sin k0 x, sin k0 y, 0) and
// grad phi2 = (eps^2 / (2 k0)) (sin k0 x cos k0 y, cos k0 x sin k0 y, 0), exactly, on the cells
// and half a cell on.
TEST(CosmologicalIcs, SecondOrderDisplacementsOfTwoWavesAreExact) {
  const int n = 32;
  const double box = 10.0, eps = 0.3, k0 = 2.0 * std::numbers::pi / box * 2.0;
  std::vector<double> delta(static_cast<std::size_t>(n) * n * n);
  auto at = [&](int i) { return (i + 0.5) * box / n; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        delta[(static_cast<std::size_t>(i) * n + j) * n + k] = eps * (std::cos(k0 * at(i)) + std::cos(k0 * at(j)));
  const ics::SpectralField field = ics::forward_transform(delta, n, box);
  for (double shift : {0.0, 0.5}) {
    const ics::Displacements d = ics::lagrangian_displacements(field, 2, shift);
    double worst = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const std::size_t c = (static_cast<std::size_t>(i) * n + j) * n + k;
          const double x = at(i) + shift * box / n, y = at(j) + shift * box / n;
          const double psi[3] = {-eps / k0 * std::sin(k0 * x), -eps / k0 * std::sin(k0 * y), 0.0};
          const double grad2[3] = {eps * eps / (2 * k0) * std::sin(k0 * x) * std::cos(k0 * y),
                                   eps * eps / (2 * k0) * std::cos(k0 * x) * std::sin(k0 * y), 0.0};
          for (int a = 0; a < 3; ++a) {
            worst = std::max(worst, std::fabs(d.first[a][c] - psi[a]));
            worst = std::max(worst, std::fabs(d.second[a][c] - grad2[a]));
          }
        }
    EXPECT_LE(worst, 1e-10) << "shift " << shift;
  }
}

// A paired partner is the same field with its sign reversed, exactly, so its Zel'dovich
// velocities are the negatives of the seed's bit for bit (and its displacements to the
// rounding of adding the lattice); a fixed field keeps each mode's phase and takes the
// spectrum's own amplitude.
TEST(CosmologicalIcs, PairedAndFixedFieldsKeepTheSeedsPhases) {
  ics::CosmologicalBoxParams p;
  p.level = 4;
  p.box = 64.0;
  p.cosmology = {0.3, 0.7, 0.03, 0.6};
  p.gas = false;
  p.lpt_order = 1;
  const ics::SpectralField seed = ics::linear_density(p);
  ics::CosmologicalBoxParams inverted = p;
  inverted.invert_phases = true;
  const ics::SpectralField partner = ics::linear_density(inverted);
  ics::CosmologicalBoxParams fixed = p;
  fixed.fix_amplitudes = true;
  const ics::SpectralField fixed_field = ics::linear_density(fixed);
  const cosmology::LinearPowerSpectrum power(cosmology::EisensteinHu(p.cosmology, p.transfer), p.n_s, p.sigma_8);
  const int n = p.cells();
  const double cell_volume = std::pow(p.box / n, 3);
  int modes = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k) {
        const std::size_t c = seed.index(i, j, k);
        EXPECT_EQ(partner.values[c], -seed.values[c]) << i << " " << j << " " << k;
        const double kk = std::sqrt(std::pow(seed.wave(i), 2) + std::pow(seed.wave(j), 2) + std::pow(seed.wave(k), 2));
        if (kk == 0.0 || seed.nyquist(i, j, k)) continue;
        ++modes;
        // |delta_k|^2 = P(k) / Delta^3 times the unit noise's mean |w_k|^2 = N^3.
        EXPECT_NEAR(std::norm(fixed_field.values[c]) / (power(kk) / cell_volume * n * n * n), 1.0, 1e-12);
        const std::complex<double> a = fixed_field.values[c] / std::abs(fixed_field.values[c]),
                                   b = seed.values[c] / std::abs(seed.values[c]);
        EXPECT_LT(std::abs(a - b), 1e-12) << "phase of mode " << i << " " << j << " " << k;
      }
  EXPECT_GT(modes, 1000);
  const ics::CosmologicalBox a = ics::make_cosmological_box(p, Units{});
  const ics::CosmologicalBox b = ics::make_cosmological_box(inverted, Units{});
  const double spacing = p.box / n;
  double largest = 0.0;
  for (std::size_t c = 0; c < a.dark_matter.size(); ++c) {
    const std::size_t ii = c / (n * n), jj = (c / n) % n, kk = c % n;
    const Vec3 q = Vec3{ii + 0.5, jj + 0.5, kk + 0.5} * spacing;
    for (int axis = 0; axis < 3; ++axis) {
      double da = a.dark_matter.x[c][axis] - q[axis], db = b.dark_matter.x[c][axis] - q[axis];
      da -= p.box * std::round(da / p.box);  // positions are folded into the box
      db -= p.box * std::round(db / p.box);
      EXPECT_NEAR(da, -db, 1e-12 * p.box) << "particle " << c;
      EXPECT_EQ(a.dark_matter.v[c][axis], -b.dark_matter.v[c][axis]) << "particle " << c;
      largest = std::max(largest, std::fabs(da));
    }
  }
  EXPECT_GT(largest, 1e-3 * spacing);  // the field moved the particles at all
}

// The particles' own power spectrum (64^3 in 256 Mpc/h; CIC on a mesh twice as fine, divided by the assignment
// window) against the input field's realised power scaled to the starting time, per shell of
// width k_f up to half the particles' Nyquist wave number: within 5%.
TEST(CosmologicalIcs, ParticlesCarryTheInputPowerSpectrum) {
  ics::CosmologicalBoxParams p;
  p.level = 6;
  p.box = 256.0;
  p.a_start = 0.02;
  p.seed = 3;
  p.cosmology = {0.3, 0.7, 0.03, 0.6};
  p.gas = false;
  const ics::CosmologicalBox box = ics::make_cosmological_box(p, Units{});
  const int n = p.cells(), mesh = 2 * n;
  std::vector<double> rho(static_cast<std::size_t>(mesh) * mesh * mesh, 0.0);
  const double cell = p.box / mesh;
  for (const Vec3& x : box.dark_matter.x) {
    int i0[3];
    double w1[3];
    for (int a = 0; a < 3; ++a) {
      const double u = x[a] / cell - 0.5;
      const double f = std::floor(u);
      i0[a] = static_cast<int>(f);
      w1[a] = u - f;
    }
    for (int c = 0; c < 8; ++c) {
      double w = 1.0;
      std::size_t idx = 0;
      for (int a = 0; a < 3; ++a) {
        const int bit = (c >> a) & 1;
        w *= bit ? w1[a] : 1.0 - w1[a];
        idx = idx * mesh + static_cast<std::size_t>(((i0[a] + bit) % mesh + mesh) % mesh);
      }
      rho[idx] += w;
    }
  }
  const double mean = static_cast<double>(box.dark_matter.size()) / rho.size();
  for (double& r : rho) r = r / mean - 1.0;
  const ics::SpectralField measured = ics::forward_transform(rho, mesh, p.box);
  const ics::SpectralField input = ics::linear_density(p);
  const cosmology::Background bg(p.cosmology);
  const double growth = bg.growth(p.a_start) / bg.growth(1.0);
  const double kf = 2.0 * std::numbers::pi / p.box;
  const int shells = n / 4;  // half the particles' Nyquist wave number, n/2 k_f
  std::vector<double> got(shells + 1, 0.0), want(shells + 1, 0.0);
  auto sinc = [](double x) { return x == 0.0 ? 1.0 : std::sin(x) / x; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k) {
        if (input.nyquist(i, j, k)) continue;
        const int mi = i <= n / 2 ? i : i - n, mj = j <= n / 2 ? j : j - n;
        const double kk = std::sqrt(double(mi * mi + mj * mj + k * k));
        const int shell = static_cast<int>(std::lround(kk));
        if (shell < 1 || shell > shells) continue;
        // The same mode on the finer mesh, with its CIC window.
        const int fi = mi >= 0 ? mi : mi + mesh, fj = mj >= 0 ? mj : mj + mesh;
        const double cell_phase = std::numbers::pi / mesh;
        const double window = std::pow(sinc(mi * cell_phase) * sinc(mj * cell_phase) * sinc(k * cell_phase), 2);
        // The finer mesh's coefficients sum over 8 times the cells of the particle grid.
        const double m = std::abs(measured.values[measured.index(fi, fj, k)]) / window / 8.0;
        got[shell] += m * m;
        want[shell] += std::norm(input.values[input.index(i, j, k)]) * growth * growth;
      }
  double worst = 0.0;
  for (int s = 1; s <= shells; ++s) {
    EXPECT_NEAR(got[s] / want[s], 1.0, 0.05) << "shell " << s << " of " << kf;
    worst = std::max(worst, std::fabs(got[s] / want[s] - 1.0));
  }
  std::printf("64^3 in 256 Mpc/h: particle power over input power within %.2f%% in %d shells\n", 100.0 * worst,
              shells);
  // Generating again gives the same bits.
  const ics::CosmologicalBox again = ics::make_cosmological_box(p, Units{});
  EXPECT_EQ(again.dark_matter.x, box.dark_matter.x);
  EXPECT_EQ(again.dark_matter.v, box.dark_matter.v);
}

}  // namespace
}  // namespace fountain
