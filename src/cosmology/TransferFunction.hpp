// Eisenstein & Hu (1998) matter transfer functions: the full fit with baryon wiggles, the no-wiggle and the zero-baryon forms.
#pragma once

#include <string_view>

#include "cosmology/Background.hpp"

namespace fountain::cosmology {

enum class TransferKind { full, no_wiggle, zero_baryon };
// The kinds' names on the command line and in files, in the enum's order.
inline constexpr const char* kTransferKindNames[] = {"full", "no_wiggle", "zero_baryon"};
// The kind of a name among kTransferKindNames; any other name throws std::invalid_argument.
TransferKind transfer_kind_named(std::string_view name);

class EisensteinHu {
 public:
  // The fit's scales from Omega_m, Omega_b and h (T_CMB = kCmbTemperature).
  EisensteinHu(const CosmologyParams& c, TransferKind kind = TransferKind::full);

  // T(k), k in h/Mpc; T -> 1 as k -> 0.
  double operator()(double k_h_per_mpc) const;
  TransferKind kind() const { return kind_; }

  // The fit's intermediate quantities (the authors' notation; lengths in Mpc, k in 1/Mpc).
  struct Scales {
    double one_plus_z_eq, k_eq, z_d, sound_horizon, k_silk;
    double alpha_c, beta_c, alpha_b, beta_b, beta_node;
    double alpha_gamma, sound_horizon_no_wiggle;
    double R_d, R_eq;
  };
  const Scales& scales() const { return s_; }

 private:
  double full(double k_mpc) const;
  double no_wiggle(double k_h, double omega_b) const;

  TransferKind kind_;
  double omega_m_h_ = 0.0;  // Omega_m h
  double h_ = 1.0, f_b_ = 0.0, w_m_ = 0.0, w_b_ = 0.0, theta_ = 1.0;
  Scales s_{};
};

}  // namespace fountain::cosmology
