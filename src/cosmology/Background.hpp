// The expanding background of a comoving run: E(a), cosmic time, and linear growth to second order.
#pragma once
#include "core/Units.hpp"

namespace fountain::cosmology {

// Matter + Lambda (+ curvature when they do not sum to one), w = -1, no radiation (as GADGET,
// so that initial conditions and dynamics agree).
struct CosmologyParams {
  double omega_m = 0.3;
  double omega_lambda = 0.7;
  double omega_b = 0.04;
  double hubble_param = 0.7;  // h, for conversions to physical units; H0 itself is 100 (internal)
  double omega_k() const { return 1.0 - omega_m - omega_lambda; }
};

// Internal units are h-scaled (Mpc/h, Msun/h, km/s), so H0 = 100 per internal time unit
// whatever h is.
inline constexpr double kHubbleInternal = 100.0;
// H0 = 100 km/s per Mpc/h in a unit system given in cgs without h (exactly kHubbleInternal
// in the default Mpc/h, Msun/h, km/s), and the critical density 3 H0^2 / (8 pi G) there.
double hubble0_in(const Units& units);
double critical_density0_in(const Units& units);

// The CMB's temperature today (K), as Eisenstein & Hu's transfer function takes it.
inline constexpr double kCmbTemperature = 2.728;
// Neutral primordial gas (X = 0.76): the mean particle mass of the cooling tables' coldest row.
inline constexpr double kNeutralMeanMolecularWeight = 1.1856;

struct SecondOrderGrowth {
  double d2 = 0.0;  // D2, -> -(3/7) a^2 as a -> 0
  double f2 = 0.0;  // dln D2 / dln a
};

class Background {
 public:
  explicit Background(const CosmologyParams& p, double hubble0 = kHubbleInternal);

  const CosmologyParams& params() const { return p_; }
  // The first scale factor at which E(a)^2 reaches zero (a closed universe turning around, or
  // one whose Lambda would have made it bounce), infinity if it expands for ever: the
  // background has no solution from the Big Bang beyond it. The constructor requires it
  // beyond a = 1, where growth and spectra are normalised.
  double expansion_limit() const;
  double hubble0() const { return h0_; }
  double E(double a) const;                // H(a) / H0
  double hubble(double a) const { return h0_ * E(a); }
  double dln_e_dln_a(double a) const;
  double omega_m_at(double a) const;       // Omega_m a^-3 / E^2
  double cosmic_time(double a) const;      // t(a) = int_0^a da / (a H), internal time units
  double growth(double a) const;           // D(a), normalised to D -> a as a -> 0
  double growth_rate(double a) const;      // f = dln D / dln a
  SecondOrderGrowth second_order_growth(double a) const;

 private:
  CosmologyParams p_;
  double h0_;
};

// The gas temperature (K) of a cosmological initial state at scale factor a: the CMB's until
// the gas decouples from it at 1/a_dec = 160 (Omega_b h^2 / 0.022)^(2/5), adiabatic after.
double initial_gas_temperature(const CosmologyParams& c, double a);

}  // namespace fountain::cosmology
