// The halo mass functions against COSMOLOGY.md C10.9's reference values, their normalisation, and the binned counts.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cosmology/Background.hpp"
#include "cosmology/PowerSpectrum.hpp"
#include "groups/MassFunction.hpp"

namespace fountain::groups {
namespace {

// The validation run's cosmology: (0.3, 0.7, Omega_b 0.03 in the transfer function, h 0.6,
// sigma_8 0.9, n_s 1), the full Eisenstein & Hu fit.
MassFunctionModel validation_model() {
  const cosmology::CosmologyParams c{0.3, 0.7, 0.03, 0.6};
  const double rho_bar = 0.3 * cosmology::critical_density0_in(Units{});  // Msun/h per (Mpc/h)^3
  return MassFunctionModel(cosmology::LinearPowerSpectrum(cosmology::EisensteinHu(c), 1.0, 0.9), rho_bar);
}

TEST(MassFunction, ReferenceValuesOfTheValidationCosmology) {
  const MassFunctionModel model = validation_model();
  struct Row {
    double mass, sigma, slope, st, j01;
  };
  // COSMOLOGY.md C10.9 (checked there): sigma, dln(1/sigma)/dln M, dn/dln M (h/Mpc)^3.
  const Row rows[] = {{1e12, 2.34070, 0.14906, 3.7816e-3, 3.8920e-3},
                      {1e13, 1.60882, 0.17794, 4.7319e-4, 4.6645e-4},
                      {1e14, 1.02385, 0.21657, 4.4854e-5, 4.9796e-5}};
  for (const Row& r : rows) {
    SCOPED_TRACE(r.mass);
    EXPECT_NEAR(model.sigma(r.mass) / r.sigma, 1.0, 1e-5);
    EXPECT_NEAR(model.slope(r.mass) / r.slope, 1.0, 5e-5);
    EXPECT_NEAR(model.dn_dln_mass(r.mass, MassFunctionFit::sheth_tormen) / r.st, 1.0, 2e-4);
    EXPECT_NEAR(model.dn_dln_mass(r.mass, MassFunctionFit::jenkins) / r.j01, 1.0, 2e-4);
  }
}

TEST(MassFunction, ShethTormenIsNormalisedAndJenkinsStaysInItsRange) {
  // int f dln(1/sigma) over ln(1/sigma) in [-40, 6] (Simpson, 9200 intervals) plus the tail
  // below, where f falls as exp(0.4 ln(1/sigma)) (f ~ nu^(1 - 2p)): one to 1e-9.
  const double a = -40.0, b = 6.0;
  const int n = 9200;
  const double step = (b - a) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double w = i == 0 || i == n ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += w * sheth_tormen_multiplicity(std::exp(-(a + i * step)));
  }
  const double tail = sheth_tormen_multiplicity(std::exp(-a)) / 0.4;
  EXPECT_NEAR(sum * step / 3.0 + tail, 1.0, 1e-9);
  EXPECT_TRUE(std::isnan(jenkins_multiplicity(std::exp(1.21))));   // ln(1/sigma) = -1.21
  EXPECT_TRUE(std::isnan(jenkins_multiplicity(std::exp(-1.06))));  // 1.06
  EXPECT_NEAR(jenkins_multiplicity(std::exp(0.61)), 0.315, 1e-15);  // the fit's peak
}

TEST(MassFunction, BinsCountEachMassOnceAndExpectTheIntegral) {
  const MassFunctionModel model = validation_model();
  const double volume = 1e6;  // (100 Mpc/h)^3
  const std::vector<double> masses{1e12, 3e12, 3.1e12, 9.99e12, 1e13, 2e15, 0.0, 5e11};
  const auto bins = bin_mass_function(masses, volume, model, 12.0, 13.5, 0.5);
  ASSERT_EQ(bins.size(), 3u);
  EXPECT_EQ(bins[0].count, 3u);  // 1e12, 3e12, 3.1e12
  EXPECT_EQ(bins[1].count, 1u);  // 9.99e12
  EXPECT_EQ(bins[2].count, 1u);  // 1e13; 2e15 lies beyond the last bin, 0 and 5e11 before the first
  // C10.9's rough counts per 0.25 dex in (100 Mpc/h)^3, 630 at 10^12.35-12.6, 220 at 12.85-13.1
  // and 72 at 13.35-13.6, are V dn/dln M at each bin's upper edge times its width in ln M; the
  // bins' integrals lie between the values at their two edges.
  const auto quarter = bin_mass_function({}, volume, model, 12.35, 13.6, 0.25);
  ASSERT_EQ(quarter.size(), 5u);
  const double width = 0.25 * std::log(10.0);
  const double rough[] = {630.0, 0.0, 220.0, 0.0, 72.0};
  for (std::size_t k = 0; k < quarter.size(); ++k) {
    const double at_hi = volume * width * model.dn_dln_mass(std::pow(10.0, quarter[k].log_hi), MassFunctionFit::jenkins);
    const double at_lo = volume * width * model.dn_dln_mass(std::pow(10.0, quarter[k].log_lo), MassFunctionFit::jenkins);
    if (rough[k] > 0.0) {
      EXPECT_NEAR(at_hi / rough[k], 1.0, 0.03);
    }
    EXPECT_GT(quarter[k].jenkins, at_hi);
    EXPECT_LT(quarter[k].jenkins, at_lo);
  }
  // The integral of a smooth function: the midpoint value times the width, to a few per cent.
  for (const auto& b : quarter) {
    const double mid = std::pow(10.0, 0.5 * (b.log_lo + b.log_hi));
    EXPECT_NEAR(b.sheth_tormen / (volume * model.dn_dln_mass(mid, MassFunctionFit::sheth_tormen) * 0.25 * std::log(10.0)),
                1.0, 0.03);
  }
}

}  // namespace
}  // namespace fountain::groups
