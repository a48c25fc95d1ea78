// The comoving leapfrog's drift and kick factors, tabulated in ln a so that steps telescope.
#pragma once
#include <array>
#include <vector>

#include "cosmology/Background.hpp"

namespace fountain::cosmology {

// For a step from a1 to a2 (internal time units):
//   drift        int dt / a^2           = int da / (a^3 H)
//   gravity kick int dt / a             = int da / (a^2 H)
//   hydro kick   int dt / a^(3 gamma-3) = int da / (a^(3 gamma - 2) H)   (the drift for 5/3)
//   time         int dt                 = int da / (a H)
// Each is the difference of a cumulative integral F(ln a), tabulated on equal steps of ln a
// (adaptive Gauss-Kronrod per interval) and read by cubic Hermite interpolation whose node
// slopes are the exact integrands: a factor is F(ln a2) - F(ln a1), so consecutive steps sum
// to the factor of their union up to round-off.
class IntegrationFactors {
 public:
  enum Kind { drift = 0, gravity_kick = 1, hydro_kick = 2, time = 3 };

  IntegrationFactors(const Background& background, double gamma, double a_begin, double a_end,
                     int intervals = 1024);

  double factor(Kind k, double a1, double a2) const { return cumulative(k, a2) - cumulative(k, a1); }
  // F_k(ln a) - F_k(ln a_begin).
  double cumulative(Kind k, double a) const;
  // The same at ln a (what the integer timeline holds).
  double cumulative_at_ln(Kind k, double ln_a) const;
  double factor_between_ln(Kind k, double ln_a1, double ln_a2) const {
    return cumulative_at_ln(k, ln_a2) - cumulative_at_ln(k, ln_a1);
  }
  const Background& background() const { return background_; }
  // The scale factor a cosmic time t after a_begin (Newton on the time table).
  double scale_factor_after(double t) const;
  double a_begin() const { return a_begin_; }
  double a_end() const { return a_end_; }

 private:
  double slope(Kind k, double a) const;  // dF_k / dln a

  const Background& background_;
  double gamma_, a_begin_, a_end_, ln_begin_, step_;
  std::array<std::vector<double>, 4> table_;
  // The Hermite slopes at the nodes, slope(k, a_i) * step_: computed once, since every drift
  // and kick reads two of them (an exp and a square root each).
  std::array<std::vector<double>, 4> node_slope_;
};

}  // namespace fountain::cosmology
