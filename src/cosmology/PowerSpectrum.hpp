// The linear matter power spectrum P(k) = A k^n_s T(k)^2 at z = 0, normalised to sigma_8.
#pragma once
#include <functional>

#include "cosmology/TransferFunction.hpp"

namespace fountain::cosmology {

// sigma^2(R) = (1/(2 pi^2)) int k^2 P(k) W_TH(kR)^2 dk for a spectrum P (k in h/Mpc, R in
// Mpc/h), integrated in ln k over 1e-6 .. 1e5 h/Mpc (Simpson, 64 points per e-fold).
double top_hat_variance(const std::function<double(double)>& power, double radius);

class LinearPowerSpectrum {
 public:
  // A is set so that sigma(8 Mpc/h) = sigma_8.
  LinearPowerSpectrum(const EisensteinHu& transfer, double n_s, double sigma_8);
  double operator()(double k) const;  // (Mpc/h)^3, k in h/Mpc
  double amplitude() const { return amplitude_; }
  double sigma(double radius) const;  // of the normalised spectrum, at z = 0

 private:
  EisensteinHu transfer_;
  double n_s_;
  double amplitude_ = 1.0;
};

}  // namespace fountain::cosmology
