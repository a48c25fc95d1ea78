// The star formation recipe as pure functions: when gas may form stars, and how fast (docs/physics.md, star formation).
#pragma once
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
};

}  // namespace fountain::star_formation
