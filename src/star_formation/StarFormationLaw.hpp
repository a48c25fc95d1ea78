// The star formation recipe and the feedback phase rules as pure functions (docs/physics.md sections 5-6).
#pragma once
#include <algorithm>
#include <cmath>
#include <numbers>

namespace fountain::star_formation {

// Why gas does or does not form stars: the paper's conditions (a)-(d), checked in order.
enum class Eligibility { Eligible, NotConverging, TooSparse, PressureSupported, TooHot };

// What the conditions read, in internal units (temperature in K).
struct GasState {
  double div_v = 0.0;
  double rho = 0.0;          // gas density (physical)
  double h = 0.0;            // smoothing length (compact support)
  double sound_speed = 0.0;
  double temperature = 0.0;
};

struct StarFormationLaw {
  double efficiency = 0.1;        // c*
  double rho_threshold = 0.0;     // rho*, internal units
  double t_threshold = 4e4;       // T*, K
  double G = 1.0;

  double dynamical_time(double rho) const { return 1.0 / std::sqrt(4.0 * std::numbers::pi * G * rho); }

  Eligibility check(const GasState& s) const {
    if (!(s.div_v < 0.0)) return Eligibility::NotConverging;
    if (!(s.rho > rho_threshold)) return Eligibility::TooSparse;
    // Sound crossing time h/c_s longer than t_dyn: pressure cannot stop the collapse.
    if (!(s.h > s.sound_speed * dynamical_time(s.rho))) return Eligibility::PressureSupported;
    if (!(s.temperature < t_threshold)) return Eligibility::TooHot;
    return Eligibility::Eligible;
  }

  // Stellar mass formed over dt at dM/dt = c* M / t_dyn, integrated exactly with rho fixed.
  double mass_formed(double m_gas, double rho, double dt) const {
    return -m_gas * std::expm1(-efficiency * dt / dynamical_time(rho));
  }

  // Feedback's cold phase: rho > 0.1 rho* and T < 2 T*. Everything else is hot.
  bool feedback_cold(double rho, double temperature) const {
    return rho > 0.1 * rho_threshold && temperature < 2.0 * t_threshold;
  }
};

// Supernova energy e_sn dM split among the three channels of MFB.
struct FeedbackShares {
  double own = 0.0;        // 1 - eps_c - eps_h: the particle's own thermal energy
  double reservoir = 0.0;  // eps_c
  double hot = 0.0;        // eps_h: the nearest hot neighbours
};

inline FeedbackShares split_feedback(double energy, double eps_cold, double eps_hot) {
  FeedbackShares s;
  s.reservoir = eps_cold * energy;
  s.hot = eps_hot * energy;
  s.own = energy - s.reservoir - s.hot;
  return s;
}

// T_prom = max(factor T*, hot_factor x mean T of the hot neighbours); mean_hot < 0: none found.
inline double promotion_temperature(double t_star, double factor, double hot_factor, double mean_hot) {
  return std::max(factor * t_star, mean_hot > 0.0 ? hot_factor * mean_hot : 0.0);
}

}  // namespace fountain::star_formation
