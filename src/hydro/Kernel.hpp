// The cubic-spline (M4) SPH kernel in GADGET's convention: compact support radius h.
#pragma once
#include <numbers>

namespace fountain::kernel {

inline constexpr double norm = 8.0 / std::numbers::pi;           // 3D normalisation
inline constexpr double volume_factor = 4.0 * std::numbers::pi / 3.0;  // neighbour number = this h^3 sum W

// W(r, h) and dW/dr for q = r/h < 1; both zero outside. `h_inv` = 1/h.
inline void eval(double r, double h_inv, double& w, double& dw_dr) {
  const double q = r * h_inv;
  const double h3 = h_inv * h_inv * h_inv;
  if (q < 0.5) {
    w = norm * h3 * (1.0 - 6.0 * q * q + 6.0 * q * q * q);
    dw_dr = norm * h3 * h_inv * (-12.0 * q + 18.0 * q * q);
  } else if (q < 1.0) {
    const double t = 1.0 - q;
    w = norm * h3 * 2.0 * t * t * t;
    dw_dr = norm * h3 * h_inv * (-6.0 * t * t);
  } else {
    w = 0.0;
    dw_dr = 0.0;
  }
}

inline double value(double r, double h_inv) {
  double w, dw;
  eval(r, h_inv, w, dw);
  return w;
}

inline double derivative(double r, double h_inv) {
  double w, dw;
  eval(r, h_inv, w, dw);
  return dw;
}

// dW/dh at fixed r: W = h^-3 f(r/h) gives -(3 W + r dW/dr) / h.
inline double dh(double r, double h_inv, double w, double dw_dr) { return -(3.0 * w + r * dw_dr) * h_inv; }

}  // namespace fountain::kernel
