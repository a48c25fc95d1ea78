#include "cosmology/TransferFunction.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fountain::cosmology {

TransferKind transfer_kind_named(std::string_view name) {
  for (std::size_t k = 0; k < std::size(kTransferKindNames); ++k)
    if (name == kTransferKindNames[k]) return static_cast<TransferKind>(k);
  throw std::invalid_argument("unknown transfer function '" + std::string(name) + "'");
}

namespace {

// T0(q; alpha, beta): the pressureless part's shape (EH98 eq. 19-20).
double t0(double q, double alpha, double beta) {
  const double l = std::log(std::numbers::e + 1.8 * beta * q);
  const double c = 14.2 / alpha + 386.0 / (1.0 + 69.9 * std::pow(q, 1.08));
  return l / (l + c * q * q);
}

}  // namespace

EisensteinHu::EisensteinHu(const CosmologyParams& c, TransferKind kind) : kind_(kind) {
  h_ = c.hubble_param;
  const double omega_b = kind == TransferKind::zero_baryon ? 0.0 : c.omega_b;
  w_m_ = c.omega_m * h_ * h_;
  w_b_ = omega_b * h_ * h_;
  f_b_ = omega_b / c.omega_m;
  omega_m_h_ = c.omega_m * h_;
  theta_ = kCmbTemperature / 2.7;
  const double t2 = theta_ * theta_, t4 = t2 * t2;
  Scales& s = s_;
  s.one_plus_z_eq = 2.50e4 * w_m_ / t4;
  s.k_eq = 7.46e-2 * w_m_ / t2;
  const double b1 = 0.313 * std::pow(w_m_, -0.419) * (1.0 + 0.607 * std::pow(w_m_, 0.674));
  const double b2 = 0.238 * std::pow(w_m_, 0.223);
  s.z_d = 1291.0 * std::pow(w_m_, 0.251) / (1.0 + 0.659 * std::pow(w_m_, 0.828)) * (1.0 + b1 * std::pow(w_b_, b2));
  s.R_d = 31.5 * w_b_ / t4 * 1000.0 / (1.0 + s.z_d);
  s.R_eq = 31.5 * w_b_ / t4 * 1000.0 / s.one_plus_z_eq;
  s.sound_horizon = s.R_eq > 0.0 ? 2.0 / (3.0 * s.k_eq) * std::sqrt(6.0 / s.R_eq) *
                                       std::log((std::sqrt(1.0 + s.R_d) + std::sqrt(s.R_d + s.R_eq)) /
                                                (1.0 + std::sqrt(s.R_eq)))
                                 : 0.0;
  s.k_silk = 1.6 * std::pow(w_b_, 0.52) * std::pow(w_m_, 0.73) * (1.0 + std::pow(10.4 * w_m_, -0.95));
  const double a1 = std::pow(46.9 * w_m_, 0.670) * (1.0 + std::pow(32.1 * w_m_, -0.532));
  const double a2 = std::pow(12.0 * w_m_, 0.424) * (1.0 + std::pow(45.0 * w_m_, -0.582));
  s.alpha_c = std::pow(a1, -f_b_) * std::pow(a2, -f_b_ * f_b_ * f_b_);
  const double c1 = 0.944 / (1.0 + std::pow(458.0 * w_m_, -0.708));
  const double c2 = std::pow(0.395 * w_m_, -0.0266);
  s.beta_c = 1.0 / (1.0 + c1 * (std::pow(1.0 - f_b_, c2) - 1.0));
  const double y = s.one_plus_z_eq / (1.0 + s.z_d);
  const double sy = std::sqrt(1.0 + y);
  const double g = y * (-6.0 * sy + (2.0 + 3.0 * y) * std::log((sy + 1.0) / (sy - 1.0)));
  s.alpha_b = 2.07 * s.k_eq * s.sound_horizon * std::pow(1.0 + s.R_d, -0.75) * g;
  s.beta_b = 0.5 + f_b_ + (3.0 - 2.0 * f_b_) * std::sqrt(17.2 * w_m_ * 17.2 * w_m_ + 1.0);
  s.beta_node = 8.41 * std::pow(w_m_, 0.435);
  s.alpha_gamma = 1.0 - 0.328 * std::log(431.0 * w_m_) * f_b_ + 0.38 * std::log(22.3 * w_m_) * f_b_ * f_b_;
  s.sound_horizon_no_wiggle = 44.5 * std::log(9.83 / w_m_) / std::sqrt(1.0 + 10.0 * std::pow(w_b_, 0.75));
}

double EisensteinHu::full(double k) const {
  const Scales& s = s_;
  const double q = k / (13.41 * s.k_eq);
  const double ks = k * s.sound_horizon;
  const double f = 1.0 / (1.0 + std::pow(ks / 5.4, 4));
  const double t_c = f * t0(q, 1.0, s.beta_c) + (1.0 - f) * t0(q, s.alpha_c, s.beta_c);
  if (f_b_ == 0.0) return t_c;
  const double s_tilde = s.sound_horizon / std::cbrt(1.0 + std::pow(s.beta_node / ks, 3));
  const double ks_tilde = k * s_tilde;
  const double t_b = (t0(q, 1.0, 1.0) / (1.0 + (ks / 5.2) * (ks / 5.2)) +
                      s.alpha_b / (1.0 + std::pow(s.beta_b / ks, 3)) * std::exp(-std::pow(k / s.k_silk, 1.4))) *
                     std::sin(ks_tilde) / ks_tilde;
  return f_b_ * t_b + (1.0 - f_b_) * t_c;
}

double EisensteinHu::no_wiggle(double k_h, double omega_b) const {
  const double k_mpc = k_h * h_;
  const double alpha = omega_b > 0.0 ? s_.alpha_gamma : 1.0;
  const double gamma_eff =
      omega_m_h_ * (alpha + (1.0 - alpha) / (1.0 + std::pow(0.43 * k_mpc * s_.sound_horizon_no_wiggle, 4)));
  const double q = k_h * theta_ * theta_ / gamma_eff;
  const double l0 = std::log(2.0 * std::numbers::e + 1.8 * q);
  const double c0 = 14.2 + 731.0 / (1.0 + 62.5 * q);
  return l0 / (l0 + c0 * q * q);
}

double EisensteinHu::operator()(double k_h) const {
  if (!(k_h > 0.0)) return 1.0;
  switch (kind_) {
    case TransferKind::full: return full(k_h * h_);
    case TransferKind::no_wiggle: return no_wiggle(k_h, f_b_);
    case TransferKind::zero_baryon: return no_wiggle(k_h, 0.0);
  }
  return 1.0;
}

}  // namespace fountain::cosmology
