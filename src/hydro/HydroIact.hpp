// SPH interactions between two particles: pure functions that the cell loops call.
#pragma once
#include <algorithm>
#include <cmath>

#include "core/Vec3.hpp"
#include "hydro/HydroParams.hpp"
#include "hydro/Kernel.hpp"

namespace fountain::hydro {

// ---------------------------------------------------------------- density loop (gather)

// Sums over the coupled neighbours j of particle i, at i's smoothing length.
struct DensitySums {
  double rho = 0.0;     // sum m_j W(r_ij, h_i)
  double w = 0.0;       // sum W
  double w_dh = 0.0;    // sum dW/dh
  double div = 0.0;     // sum m_j W'/r (v_ij . x_ij)
  Vec3 curl;            // sum m_j W'/r (x_ij x v_ij)
};

// dx = x_i - x_j, dv = v_i - v_j, r2 = |dx|^2 < h_i^2.
inline void iact_density(const Vec3& dx, const Vec3& dv, double r2, double hi_inv, double mj,
                         DensitySums& s) {
  const double r = std::sqrt(r2);
  double w, dw;
  kernel::eval(r, hi_inv, w, dw);
  s.rho += mj * w;
  s.w += w;
  s.w_dh += kernel::dh(r, hi_inv, w, dw);
  if (r > 0.0) {
    const double f = mj * dw / r;
    s.div += f * dot(dv, dx);
    s.curl += f * cross(dx, dv);
  }
}

// The density-loop results of particle i from its sums.
struct DensityResult {
  double rho, wcount, wcount_dh, div_v;
  Vec3 curl_v;
};

inline DensityResult finish_density(const DensitySums& s, double h) {
  const double h3 = h * h * h;
  DensityResult r;
  r.rho = s.rho;
  r.wcount = kernel::volume_factor * h3 * s.w;
  r.wcount_dh = kernel::volume_factor * (3.0 * h * h * s.w + h3 * s.w_dh);
  r.div_v = s.rho > 0.0 ? -s.div / s.rho : 0.0;
  r.curl_v = s.rho > 0.0 ? s.curl * (1.0 / s.rho) : Vec3{};
  return r;
}

// ---------------------------------------------------------------- the MSPH rule

// What the MSPH rule reads of a particle: frozen predicted values for the whole step.
struct MsphState {
  double rho, u, h, c;
};

// mu_ij of the viscosity (paper eq. 8): negative when approaching, else zero.
inline double mu_ij(const Vec3& dx, const Vec3& dv, double r2, double h_ij) {
  const double vr = dot(dv, dx);
  return vr < 0.0 ? h_ij * vr / (r2 + 0.01 * h_ij * h_ij) : 0.0;
}

// D(i,j) of the paper: i ignores the much denser, much colder j unless they shock together.
inline bool msph_ignores(const MsphState& i, const MsphState& j, double mu, double c_ij,
                         const HydroParams& p) {
  return j.rho > p.msph_A * i.rho && j.u < i.u / p.msph_A_prime && mu > -c_ij;
}

// Whether the pair is decoupled: symmetric in i and j, so Newton's third law holds.
inline bool msph_decoupled(const MsphState& i, const MsphState& j, const Vec3& dx, const Vec3& dv,
                           double r2, const HydroParams& p) {
  if (!p.msph) return false;
  if (!(j.rho > p.msph_A * i.rho || i.rho > p.msph_A * j.rho)) return false;  // cheap reject
  const double mu = mu_ij(dx, dv, r2, 0.5 * (i.h + j.h));
  const double c_ij = 0.5 * (i.c + j.c);
  return msph_ignores(i, j, mu, c_ij, p) || msph_ignores(j, i, mu, c_ij, p);
}

inline double pressure(double rho, double u, double gamma) { return (gamma - 1.0) * rho * u; }
inline double sound_speed(double rho, double u, double gamma) {
  return rho > 0.0 ? std::sqrt(gamma * pressure(rho, u, gamma) / rho) : 0.0;
}

// rho^a with the common a = 3/2 done without pow, the same way everywhere.
inline double rho_power(double rho, double a) {
  if (a == 1.5) return rho * std::sqrt(rho);
  if (a == 0.5) return std::sqrt(rho);
  if (a == 1.0) return rho;
  if (a == 2.0) return rho * rho;
  return std::pow(rho, a);
}

// ---------------------------------------------------------------- force loop (gather)

// Per-particle inputs of the force loop, derived from the state once per particle.
struct ForceState {
  Vec3 v;
  double m, rho, h, pressure, c, rho_a, rho_2ma, balsara;
};

inline ForceState make_force_state(const Vec3& v, double m, double rho, double u, double h,
                                   double div_v, const Vec3& curl_v, const HydroParams& p) {
  ForceState s;
  s.v = v;
  s.m = m;
  s.rho = rho;
  s.h = h;
  s.pressure = pressure(rho, u, p.gamma);
  s.c = sound_speed(rho, u, p.gamma);
  s.rho_a = rho_power(rho, p.sph_alpha);
  s.rho_2ma = rho_power(rho, 2.0 - p.sph_alpha);
  const double adiv = std::fabs(div_v);
  const double denom = adiv + norm(curl_v) + 1e-4 * s.c / h;
  s.balsara = denom > 0.0 ? adiv / denom : 0.0;
  return s;
}

struct ForceSums {
  Vec3 a;
  double du_dt = 0.0;
};

// The pair terms of paper eqs 1-2 (general alpha, Balsara-corrected viscosity), added to i.
// dx = x_i - x_j; r2 < max(h_i, h_j)^2. Every term is symmetric in (i, j) up to the sign of
// dx, so the pair force is exactly antisymmetric in floating point.
inline void iact_force(const ForceState& i, const ForceState& j, const Vec3& dx, double r2,
                       const HydroParams& p, ForceSums& s) {
  const double r = std::sqrt(r2);
  if (r == 0.0) return;
  const double dwi = r < i.h ? kernel::derivative(r, 1.0 / i.h) : 0.0;
  const double dwj = r < j.h ? kernel::derivative(r, 1.0 / j.h) : 0.0;
  const double dw_mean_over_r = 0.5 * (dwi + dwj) / r;  // grad W_ij = this * dx

  const Vec3 dv = i.v - j.v;
  const double h_ij = 0.5 * (i.h + j.h);
  const double mu = mu_ij(dx, dv, r2, h_ij);
  const double c_ij = 0.5 * (i.c + j.c);
  double visc = 0.0;
  if (mu < 0.0) {
    const double alpha = p.viscosity_alpha;
    visc = (-alpha * c_ij * mu + 2.0 * alpha * mu * mu) / (0.5 * (i.rho + j.rho)) *
           (0.5 * (i.balsara + j.balsara));
  }
  const double p_ij = j.pressure / (i.rho_2ma * j.rho_a);  // P_j / (rho_i^(2-a) rho_j^a)
  const double p_ji = i.pressure / (j.rho_2ma * i.rho_a);  // P_i / (rho_j^(2-a) rho_i^a)
  const double f = j.m * ((p_ij + p_ji) + visc) * dw_mean_over_r;
  s.a -= dx * f;
  s.du_dt += j.m * (p_ji + 0.5 * visc) * dw_mean_over_r * dot(dv, dx);
}

// ---------------------------------------------------------------- timestep

// Courant criterion of the paper (GADGET-1 form, PHYSICS.md section 3).
inline double courant_timestep(double h, double div_v, double c, double speed, const HydroParams& p) {
  const double denom = h * std::fabs(div_v) + std::max(c, speed) * (1.0 + 0.6 * p.viscosity_alpha);
  return denom > 0.0 ? p.courant * h / denom : std::numeric_limits<double>::infinity();
}

}  // namespace fountain::hydro
