// SPH interactions between two particles: pure functions that the cell loops call.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "core/ScratchArray.hpp"
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

// ---------------------------------------------------------------- velocity gradient

// The symmetric part S of a particle's velocity gradient (per unit length of the position
// variable), kept for the viscosity's reconstruction (hydro.viscosity_reconstruction): only
// x^T S x enters it, and the antisymmetric part (rotation) adds nothing to that.
struct StrainRate {
  Vec3 diagonal;  // S_xx, S_yy, S_zz
  Vec3 shear;     // S_xy, S_xz, S_yz
};

// x^T S x: the rate at which the flow about the particle stretches the separation x.
inline double stretch(const StrainRate& s, double x, double y, double z) {
  return s.diagonal.x * x * x + s.diagonal.y * y * y + s.diagonal.z * z * z +
         2.0 * (s.shear.x * x * y + s.shear.y * x * z + s.shear.z * y * z);
}

// Sums for particle i's velocity gradient, with w_ij = m_j W'(r_ij, h_i) / r_ij, dx = x_i - x_j,
// dv = v_i - v_j: D = sum w dv dx^T and C = sum w dx dx^T. G = D C^-1 is exact for any linear
// velocity field whatever the neighbours' arrangement (C corrects the kernel's first moment),
// which the plain SPH estimate is not on a stretched lattice.
struct GradientSums {
  double d[9]{};  // D, row-major: d[3a + b] = sum w dv_a dx_b
  double c[6]{};  // C: xx, yy, zz, xy, xz, yz
};

inline void iact_gradient(const Vec3& dx, const Vec3& dv, double r2, double hi_inv, double mj, GradientSums& s) {
  const double r = std::sqrt(r2);
  if (r == 0.0) return;
  const double w = mj * kernel::derivative(r, hi_inv) / r;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) s.d[3 * a + b] += w * dv[a] * dx[b];
  s.c[0] += w * dx.x * dx.x, s.c[1] += w * dx.y * dx.y, s.c[2] += w * dx.z * dx.z;
  s.c[3] += w * dx.x * dx.y, s.c[4] += w * dx.x * dx.z, s.c[5] += w * dx.y * dx.z;
}

// S = sym(D C^-1). Neighbours (nearly) in a plane or on a line leave C singular: then S = 0,
// and the viscosity is the plain one.
inline StrainRate strain_rate(const GradientSums& s) {
  const double cxx = s.c[0], cyy = s.c[1], czz = s.c[2], cxy = s.c[3], cxz = s.c[4], cyz = s.c[5];
  // The adjugate of C (symmetric) and its determinant.
  const double ixx = cyy * czz - cyz * cyz, iyy = cxx * czz - cxz * cxz, izz = cxx * cyy - cxy * cxy;
  const double ixy = cxz * cyz - cxy * czz, ixz = cxy * cyz - cxz * cyy, iyz = cxy * cxz - cxx * cyz;
  const double det = cxx * ixx + cxy * ixy + cxz * ixz;
  const double mean = (cxx + cyy + czz) / 3.0;
  if (!(std::fabs(det) > 1e-3 * std::fabs(mean * mean * mean))) return {};
  const double inv[9] = {ixx / det, ixy / det, ixz / det, ixy / det, iyy / det, iyz / det, ixz / det, iyz / det, izz / det};
  double g[9];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      g[3 * a + b] = s.d[3 * a] * inv[b] + s.d[3 * a + 1] * inv[3 + b] + s.d[3 * a + 2] * inv[6 + b];
  return {{g[0], g[4], g[8]}, {0.5 * (g[1] + g[3]), 0.5 * (g[2] + g[6]), 0.5 * (g[5] + g[7])}};
}

// The approach w = v_ij . x_ij that the viscosity sees once each side's velocity is carried to
// the pair's midpoint along its own gradient (Christensen 1990; Frontiere, Raskin & Owen 2017;
// Rosswog 2020), from the pair's w and the two slopes s_i = x_ij^T S_i x_ij, s_j likewise
// (the Hubble flow's a^2 H r^2 included in a comoving run). The van Leer limiter
// 4 s_i s_j / (s_i + s_j)^2 keeps the whole reconstruction where the slopes agree (a smooth
// flow, whose linear part then leaves no viscosity) and none where they differ in sign (a
// shock). The reconstruction only ever weakens the viscosity: the result lies in [w, 0].
// Symmetric in i and j, so pair forces stay antisymmetric.
//
// A smeared shock front can look smooth to the limiter (both sides already compressing), so
// the reconstruction is also withdrawn where the pair's pressures differ by more than
// adiabatic compression explains: with entropy functions K = P / rho^gamma and pressures
// P_i, P_j, the pressure difference that is not adiabatic, dP = (P_i + P_j) |K_i - K_j| /
// (K_i + K_j), against the ram pressure of the approach, ram = rho_ij w^2 / r^2: the pair keeps
// the share x^4 of the reconstruction, x = ram / (ram + dP). Cold gas heated a little keeps it
// (its pressure is nothing against the flow's), a shock front's hot-cold pairs lose it. Both
// are comoving or both physical with the same power of a (gamma = 5/3).
// x is passed as a fraction num / den (both sides times r^2 (K_i + K_j)) so that a pair costs
// one division.
struct ShockFraction {
  double num, den;
};

inline ShockFraction shock_fraction(double ki, double kj, double pi, double pj, double rho_ij, double vr, double r2) {
  const double ram = rho_ij * vr * vr * (ki + kj);
  return {ram, ram + (pi + pj) * std::fabs(ki - kj) * r2};
}

inline double reconstructed_approach(double vr, double si, double sj, ShockFraction shock = {1.0, 1.0}) {
  const double prod = si * sj, sum = si + sj;
  // limiter (s_i + s_j) / 2 = 2 s_i s_j / (s_i + s_j); 1 / (s_i + s_j) and x from one division.
  const double q = 1.0 / (sum * shock.den);
  const double x = shock.num * sum * q;
  const double x2 = x * x;
  const double shift = prod > 0.0 && shock.den > 0.0 ? 2.0 * prod * shock.den * q * (x2 * x2) : 0.0;
  const double w = vr - shift;
  return vr < 0.0 ? std::min(0.0, std::max(vr, w)) : vr;
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

// A pair's velocity difference as viscosity and the MSPH rule see it: in a comoving run the
// peculiar v'_i - v'_j plus the Hubble flow a^2 H (x_i - x_j) between them (hubble_flow =
// a^2 H; 0 in plain time, where the difference is returned untouched).
inline Vec3 pair_flow(const Vec3& dv, const Vec3& dx, double hubble_flow) {
  return hubble_flow != 0.0 ? dv + hubble_flow * dx : dv;
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

// Per-particle inputs of the force loop, derived from the state once per particle. The
// momentum equation's P_j / (rho_i^(2-a) rho_j^a) is p_over_rho_a_j * inv_rho_2ma_i: two
// products per pair instead of two divisions.
struct ForceState {
  Vec3 v;
  double m, rho, h, c, p_over_rho_a, inv_rho_2ma, balsara;
  // Read only with hydro.viscosity_reconstruction.
  double entropy;  // K = P / rho^gamma
  StrainRate strain;
};

inline ForceState make_force_state(const Vec3& v, double m, double rho, double u, double h,
                                   double div_v, const Vec3& curl_v, const HydroParams& p,
                                   const StrainRate& strain = {}) {
  ForceState s;
  s.v = v;
  s.strain = strain;
  s.m = m;
  s.rho = rho;
  s.h = h;
  s.c = sound_speed(rho, u, p.gamma);
  s.p_over_rho_a = pressure(rho, u, p.gamma) / rho_power(rho, p.sph_alpha);
  s.inv_rho_2ma = 1.0 / rho_power(rho, 2.0 - p.sph_alpha);
  s.entropy = p.viscosity_reconstruction && rho > 0.0 ? pressure(rho, u, p.gamma) / std::pow(rho, p.gamma) : 0.0;
  const double adiv = std::fabs(div_v);
  const double denom = adiv + norm(curl_v) + 1e-4 * s.c / h;
  s.balsara = denom > 0.0 ? adiv / denom : 0.0;
  return s;
}

struct ForceSums {
  Vec3 a;
  double du_dt = 0.0;
  double v_sig = 0.0;  // the largest pair signal velocity (0 without pairs)
};

// The signal velocity of a pair (Monaghan 1997; GADGET-2, SWIFT): c_i + c_j - 3 w_ij with
// w_ij = min(0, v_ij . r_ij / |r_ij|), from vr = v_ij . r_ij and 1/|r_ij|.
inline double signal_velocity(double ci, double cj, double vr, double inv_r) {
  return ci + cj - 3.0 * std::min(0.0, vr * inv_r);
}

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
  double vr_visc = dot(dv, dx);
  if (p.viscosity_reconstruction) {
    const double inv_gamma = 1.0 / p.gamma;
    const ShockFraction shock = shock_fraction(i.entropy, j.entropy, i.rho * i.c * i.c * inv_gamma,
                                               j.rho * j.c * j.c * inv_gamma, 0.5 * (i.rho + j.rho), vr_visc, r2);
    vr_visc = reconstructed_approach(vr_visc, stretch(i.strain, dx.x, dx.y, dx.z), stretch(j.strain, dx.x, dx.y, dx.z),
                                     shock);
  }
  const double mu = vr_visc < 0.0 ? h_ij * vr_visc / (r2 + 0.01 * h_ij * h_ij) : 0.0;
  const double c_ij = 0.5 * (i.c + j.c);
  double visc = 0.0;
  if (mu < 0.0) {
    const double alpha = p.viscosity_alpha;
    visc = (-alpha * c_ij * mu + 2.0 * alpha * mu * mu) / (0.5 * (i.rho + j.rho)) *
           (0.5 * (i.balsara + j.balsara));
  }
  const double p_ij = j.p_over_rho_a * i.inv_rho_2ma;  // P_j / (rho_i^(2-a) rho_j^a)
  const double p_ji = i.p_over_rho_a * j.inv_rho_2ma;  // P_i / (rho_j^(2-a) rho_i^a)
  const double f = j.m * ((p_ij + p_ji) + visc) * dw_mean_over_r;
  s.a -= dx * f;
  s.du_dt += j.m * (p_ji + 0.5 * visc) * dw_mean_over_r * dot(dv, dx);
  s.v_sig = std::max(s.v_sig, signal_velocity(i.c, j.c, dot(dv, dx), 1.0 / r));
}

// ---------------------------------------------------------------- four pairs at once
// The loops first list all the pairs of particle i, then sum them four at a time with
// iact_density_lanes / iact_force_lanes: the same arithmetic as iact_density and iact_force,
// written without branches over plain arrays so the compiler vectorises it, and with no
// other work between batches so the square roots and divisions of one batch overlap those
// of the next. Pair m goes to lane m % 4; each lane keeps its own sums, added up in a fixed
// order at the end, so results do not depend on the machine's vector width. The last batch
// is padded with pairs that add nothing (zero mass; for density r2 = h_i^2, which the
// kernel excludes).
inline constexpr int kLanes = 4;

struct DensityLanes {
  double rho[kLanes]{}, w[kLanes]{}, w_dh[kLanes]{}, div[kLanes]{}, cx[kLanes]{}, cy[kLanes]{}, cz[kLanes]{};

  static double add(const double (&a)[kLanes]) { return (a[0] + a[1]) + (a[2] + a[3]); }
  DensitySums total() const {
    DensitySums s;
    s.rho = add(rho);
    s.w = add(w);
    s.w_dh = add(w_dh);
    s.div = add(div);
    s.curl = {add(cx), add(cy), add(cz)};
    return s;
  }
};

// The pairs (i, j) of one particle i for the density loop: dx = x_i - x_j, dv = v_i - v_j.
struct DensityPairs {
  ScratchArray<double> dx, dy, dz, r2, dvx, dvy, dvz, m;
  std::size_t n = 0;

  // Empties the list, with room for `most` pairs and the padding.
  void reset(std::size_t most) {
    n = 0;
    for (auto* a : {&dx, &dy, &dz, &r2, &dvx, &dvy, &dvz, &m}) a->ensure(most + kLanes);
  }
  void add(const Vec3& d, const Vec3& dv, double r2_value, double mj) {
    dx[n] = d.x, dy[n] = d.y, dz[n] = d.z, r2[n] = r2_value;
    dvx[n] = dv.x, dvy[n] = dv.y, dvz[n] = dv.z, m[n] = mj;
    ++n;
  }
  // Pads the last batch (h_i: i's smoothing length) and returns the padded length.
  std::size_t pad(double hi) {
    std::size_t k = n;
    for (; k % kLanes != 0; ++k) dx[k] = dy[k] = dz[k] = dvx[k] = dvy[k] = dvz[k] = m[k] = 0.0, r2[k] = hi * hi;
    return k;
  }
};

// The batch of pairs b .. b + 3; pairs with r2 >= hi^2 add nothing.
[[gnu::always_inline]] inline void iact_density_lanes(const DensityPairs& q, std::size_t b, double hi, DensityLanes& s) {
  const double hi_inv = 1.0 / hi;
  const double hi2 = hi * hi;
  const double h3 = kernel::norm * hi_inv * hi_inv * hi_inv;
  const double h4 = h3 * hi_inv;
  const double *qdx = q.dx.data() + b, *qdy = q.dy.data() + b, *qdz = q.dz.data() + b, *qr2 = q.r2.data() + b;
  const double *qvx = q.dvx.data() + b, *qvy = q.dvy.data() + b, *qvz = q.dvz.data() + b, *qm = q.m.data() + b;
  for (int l = 0; l < kLanes; ++l) {
    const double r = std::sqrt(qr2[l]);
    const double u = r * hi_inv;
    const double t = 1.0 - u;
    const bool inner = u < 0.5;
    const bool inside = qr2[l] < hi2;
    const double w = inside ? h3 * (inner ? 1.0 - 6.0 * u * u + 6.0 * u * u * u : 2.0 * t * t * t) : 0.0;
    const double dw = inside ? h4 * (inner ? -12.0 * u + 18.0 * u * u : -6.0 * t * t) : 0.0;
    const double inv_r = r > 0.0 ? 1.0 / r : 0.0;
    s.rho[l] += qm[l] * w;
    s.w[l] += w;
    s.w_dh[l] += -(3.0 * w + r * dw) * hi_inv;
    const double f = qm[l] * dw * inv_r;
    s.div[l] += f * (qvx[l] * qdx[l] + qvy[l] * qdy[l] + qvz[l] * qdz[l]);
    s.cx[l] += f * (qdy[l] * qvz[l] - qdz[l] * qvy[l]);
    s.cy[l] += f * (qdz[l] * qvx[l] - qdx[l] * qvz[l]);
    s.cz[l] += f * (qdx[l] * qvy[l] - qdy[l] * qvx[l]);
  }
}

// Particle i's density sums over its listed pairs (h_i: its smoothing length).
[[gnu::always_inline]] inline DensitySums sum_density_pairs(DensityPairs& q, double hi) {
  DensityLanes lanes;
  const std::size_t end = q.pad(hi);
  for (std::size_t b = 0; b < end; b += kLanes) iact_density_lanes(q, b, hi, lanes);
  return lanes.total();
}

struct GradientLanes {
  double d[9][kLanes]{}, c[6][kLanes]{};

  GradientSums total() const {
    GradientSums s;
    for (int k = 0; k < 9; ++k) s.d[k] = DensityLanes::add(d[k]);
    for (int k = 0; k < 6; ++k) s.c[k] = DensityLanes::add(c[k]);
    return s;
  }
};

// The velocity-gradient sums of the batch b .. b + 3 (iact_gradient's arithmetic).
[[gnu::always_inline]] inline void iact_gradient_lanes(const DensityPairs& q, std::size_t b, double hi, GradientLanes& s) {
  const double hi_inv = 1.0 / hi;
  const double hi2 = hi * hi;
  const double h4 = kernel::norm * hi_inv * hi_inv * hi_inv * hi_inv;
  const double *qdx = q.dx.data() + b, *qdy = q.dy.data() + b, *qdz = q.dz.data() + b, *qr2 = q.r2.data() + b;
  const double *qvx = q.dvx.data() + b, *qvy = q.dvy.data() + b, *qvz = q.dvz.data() + b, *qm = q.m.data() + b;
  for (int l = 0; l < kLanes; ++l) {
    const double r = std::sqrt(qr2[l]);
    const double u = r * hi_inv;
    const double t = 1.0 - u;
    const double dw = qr2[l] < hi2 ? h4 * (u < 0.5 ? -12.0 * u + 18.0 * u * u : -6.0 * t * t) : 0.0;
    const double w = r > 0.0 ? qm[l] * dw / r : 0.0;
    const double dx[3] = {qdx[l], qdy[l], qdz[l]}, dv[3] = {qvx[l], qvy[l], qvz[l]};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) s.d[3 * a + c][l] += w * dv[a] * dx[c];
    s.c[0][l] += w * dx[0] * dx[0], s.c[1][l] += w * dx[1] * dx[1], s.c[2][l] += w * dx[2] * dx[2];
    s.c[3][l] += w * dx[0] * dx[1], s.c[4][l] += w * dx[0] * dx[2], s.c[5][l] += w * dx[1] * dx[2];
  }
}

// Particle i's strain rate over its listed pairs (h_i: its smoothing length).
[[gnu::always_inline]] inline StrainRate sum_strain_pairs(DensityPairs& q, double hi) {
  GradientLanes lanes;
  const std::size_t end = q.pad(hi);
  for (std::size_t b = 0; b < end; b += kLanes) iact_gradient_lanes(q, b, hi, lanes);
  return strain_rate(lanes.total());
}

struct ForceLanes {
  double ax[kLanes]{}, ay[kLanes]{}, az[kLanes]{}, du_dt[kLanes]{}, v_sig[kLanes]{};

  ForceSums total() const {
    ForceSums s;
    s.a = {DensityLanes::add(ax), DensityLanes::add(ay), DensityLanes::add(az)};
    s.du_dt = DensityLanes::add(du_dt);
    s.v_sig = std::max(std::max(v_sig[0], v_sig[1]), std::max(v_sig[2], v_sig[3]));
    return s;
  }
};

// The pairs (i, j) of one particle i for the force loop, with j's prepared force inputs.
struct ForcePairs {
  ScratchArray<double> dx, dy, dz, r2, dvx, dvy, dvz;
  ScratchArray<double> m, rho, h, c, p_over_rho_a, inv_rho_2ma, balsara;
  // j's entropy and strain rate, listed only for the viscosity's reconstruction.
  ScratchArray<double> entropy, sxx, syy, szz, sxy, sxz, syz;
  std::size_t n = 0;

  void reset(std::size_t most, bool strain = false) {
    n = 0;
    for (auto* a : {&dx, &dy, &dz, &r2, &dvx, &dvy, &dvz, &m, &rho, &h, &c, &p_over_rho_a, &inv_rho_2ma, &balsara})
      a->ensure(most + kLanes);
    if (strain)
      for (auto* a : {&entropy, &sxx, &syy, &szz, &sxy, &sxz, &syz}) a->ensure(most + kLanes);
  }
  void add(const Vec3& d, const Vec3& dv, double r2_value, const ForceState& j) {
    dx[n] = d.x, dy[n] = d.y, dz[n] = d.z, r2[n] = r2_value;
    dvx[n] = dv.x, dvy[n] = dv.y, dvz[n] = dv.z;
    m[n] = j.m, rho[n] = j.rho, h[n] = j.h, c[n] = j.c;
    p_over_rho_a[n] = j.p_over_rho_a, inv_rho_2ma[n] = j.inv_rho_2ma, balsara[n] = j.balsara;
    ++n;
  }
  void add_strain(double entropy_j, const StrainRate& s) {
    const std::size_t k = n - 1;
    entropy[k] = entropy_j;
    sxx[k] = s.diagonal.x, syy[k] = s.diagonal.y, szz[k] = s.diagonal.z;
    sxy[k] = s.shear.x, sxz[k] = s.shear.y, syz[k] = s.shear.z;
  }
  std::size_t pad(bool strain = false) {
    std::size_t k = n;
    for (; k % kLanes != 0; ++k) {
      dx[k] = dy[k] = dz[k] = dvx[k] = dvy[k] = dvz[k] = m[k] = c[k] = 0.0;
      p_over_rho_a[k] = inv_rho_2ma[k] = balsara[k] = 0.0;
      r2[k] = rho[k] = h[k] = 1.0;
      if (strain) entropy[k] = sxx[k] = syy[k] = szz[k] = sxy[k] = sxz[k] = syz[k] = 0.0;
    }
    return k;
  }
};

// kSignalVelocity: also the largest pair signal velocity, which only the signal-velocity Courant
// criterion reads (the default criterion's loops skip it).
// kComoving: a comoving run's pairs (docs/physics.md §11): viscosity, its heating and the
// signal velocity take the pair velocity with the Hubble flow, w = v'_ij . x_ij + a^2 H r^2;
// the pressure term of the energy equation the peculiar v'_ij alone.
// kReconstruct: the viscosity sees the reconstructed approach (reconstructed_approach), the
// slopes from the listed strain rates (plus a^2 H r^2 when comoving); its heating the pair's
// own w, so the energy it takes from the motion is what it gives the gas.
template <bool kSignalVelocity, bool kComoving = false, bool kReconstruct = false>
[[gnu::always_inline]] inline void iact_force_lanes(const ForceState& i, const ForcePairs& q, std::size_t b, const HydroParams& p,
                             ForceLanes& s, double hubble_flow = 0.0) {
  const double hi_inv = 1.0 / i.h;
  const double alpha = p.viscosity_alpha;
  const double inv_gamma = 1.0 / p.gamma;
  const double *qdx = q.dx.data() + b, *qdy = q.dy.data() + b, *qdz = q.dz.data() + b, *qr2 = q.r2.data() + b;
  const double *qvx = q.dvx.data() + b, *qvy = q.dvy.data() + b, *qvz = q.dvz.data() + b;
  const double *qm = q.m.data() + b, *qrho = q.rho.data() + b, *qh = q.h.data() + b, *qc = q.c.data() + b;
  const double *qpa = q.p_over_rho_a.data() + b, *qir = q.inv_rho_2ma.data() + b, *qbal = q.balsara.data() + b;
  for (int l = 0; l < kLanes; ++l) {
    const double r2 = qr2[l];
    const double r = std::sqrt(r2);
    const double inv_r = r > 0.0 ? 1.0 / r : 0.0;
    const double hj_inv = 1.0 / qh[l];
    const double ui = r * hi_inv, uj = r * hj_inv;
    const double ti = 1.0 - ui, tj = 1.0 - uj;
    const double dwi = r < i.h ? kernel::norm * hi_inv * hi_inv * hi_inv * hi_inv *
                                     (ui < 0.5 ? -12.0 * ui + 18.0 * ui * ui : -6.0 * ti * ti)
                               : 0.0;
    const double dwj = r < qh[l] ? kernel::norm * hj_inv * hj_inv * hj_inv * hj_inv *
                                       (uj < 0.5 ? -12.0 * uj + 18.0 * uj * uj : -6.0 * tj * tj)
                                 : 0.0;
    const double dw_mean_over_r = 0.5 * (dwi + dwj) * inv_r;
    const double vr_peculiar = qvx[l] * qdx[l] + qvy[l] * qdy[l] + qvz[l] * qdz[l];
    const double vr = kComoving ? vr_peculiar + hubble_flow * r2 : vr_peculiar;
    const double h_ij = 0.5 * (i.h + qh[l]);
    double vr_visc = vr;
    if constexpr (kReconstruct) {
      const double x = qdx[l], y = qdy[l], z = qdz[l];
      const StrainRate sj{{q.sxx[b + l], q.syy[b + l], q.szz[b + l]}, {q.sxy[b + l], q.sxz[b + l], q.syz[b + l]}};
      const double hubble = kComoving ? hubble_flow * r2 : 0.0;
      const ShockFraction shock = shock_fraction(i.entropy, q.entropy[b + l], i.rho * i.c * i.c * inv_gamma,
                                                 qrho[l] * qc[l] * qc[l] * inv_gamma, 0.5 * (i.rho + qrho[l]), vr, r2);
      vr_visc = reconstructed_approach(vr, stretch(i.strain, x, y, z) + hubble, stretch(sj, x, y, z) + hubble, shock);
    }
    const double mu = vr_visc < 0.0 ? h_ij * vr_visc / (r2 + 0.01 * h_ij * h_ij) : 0.0;
    const double c_ij = 0.5 * (i.c + qc[l]);
    const double visc = mu < 0.0 ? (-alpha * c_ij * mu + 2.0 * alpha * mu * mu) / (0.5 * (i.rho + qrho[l])) *
                                       (0.5 * (i.balsara + qbal[l]))
                                 : 0.0;
    const double p_ij = qpa[l] * i.inv_rho_2ma;
    const double p_ji = i.p_over_rho_a * qir[l];
    const double f = qm[l] * ((p_ij + p_ji) + visc) * dw_mean_over_r;
    s.ax[l] -= qdx[l] * f;
    s.ay[l] -= qdy[l] * f;
    s.az[l] -= qdz[l] * f;
    if constexpr (kComoving)
      s.du_dt[l] += qm[l] * (p_ji * vr_peculiar + 0.5 * visc * vr) * dw_mean_over_r;
    else
      s.du_dt[l] += qm[l] * (p_ji + 0.5 * visc) * dw_mean_over_r * vr;
    // A padding pair (c_j = 0, at rest) gives c_i, below any real pair's value.
    if constexpr (kSignalVelocity) s.v_sig[l] = std::max(s.v_sig[l], signal_velocity(i.c, qc[l], vr, inv_r));
  }
}

// Particle i's force sums over its listed pairs.
template <bool kSignalVelocity, bool kComoving = false, bool kReconstruct = false>
[[gnu::always_inline]] inline ForceSums sum_force_pairs(const ForceState& i, ForcePairs& q, const HydroParams& p,
                                                         double hubble_flow = 0.0) {
  ForceLanes lanes;
  const std::size_t end = q.pad(kReconstruct);
  for (std::size_t b = 0; b < end; b += kLanes)
    iact_force_lanes<kSignalVelocity, kComoving, kReconstruct>(i, q, b, p, lanes, hubble_flow);
  return lanes.total();
}

// ---------------------------------------------------------------- timestep

// Courant criterion of the paper (GADGET-1 form, docs/physics.md section 3).
inline double courant_timestep(double h, double div_v, double c, double speed, const HydroParams& p) {
  const double denom = h * std::fabs(div_v) + std::max(c, speed) * (1.0 + 0.6 * p.viscosity_alpha);
  return denom > 0.0 ? p.courant * h / denom : std::numeric_limits<double>::infinity();
}

// The signal-velocity criterion of GADGET-2 and SWIFT, dt = C h / v_sig,max, with C chosen so
// that gas at rest (v_sig = 2c) gets the paper's step: C = 2 alpha_c / (1 + 0.6 alpha_v).
inline double signal_velocity_timestep(double h, double v_sig, const HydroParams& p) {
  const double c_sv = 2.0 * p.courant / (1.0 + 0.6 * p.viscosity_alpha);
  return v_sig > 0.0 ? c_sv * h / v_sig : std::numeric_limits<double>::infinity();
}

// The hydrodynamic step of the criterion in force (time_integration.courant_criterion).
inline double hydro_timestep(double h, double div_v, double c, double speed, double v_sig, const HydroParams& p) {
  return p.courant_criterion == CourantCriterion::SignalVelocity ? signal_velocity_timestep(h, v_sig, p)
                                                                 : courant_timestep(h, div_v, c, speed, p);
}

}  // namespace fountain::hydro
