// GADGET-2's cubic-spline softened gravity between two point masses, and the TreePM split hook.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace fountain::gravity {

// Softening lengths are given as the Plummer-equivalent eps everywhere (that is what
// docs/physics.md and the parameter files quote); the spline reaches Newtonian at h = 2.8 eps.
inline constexpr double kSplineFactor = 2.8;

constexpr double spline_length(double eps) { return kSplineFactor * eps; }

// Two particles interact with the larger of their softenings: the rule is symmetric in
// (i, j), so the two forces of a pair are exactly opposite and momentum is conserved.
constexpr double pair_spline_length(double eps_i, double eps_j) {
  return spline_length(std::max(eps_i, eps_j));
}

// 1 / max(h_i, h_j) from the particles' 1 / h, bit for bit: rounded division is monotone,
// so 1 / max(a, b) == min(1 / a, 1 / b) exactly. Loops that keep each particle's inverse
// spline length then pay no division per pair for it.
template <class Real>
constexpr Real pair_inverse_spline_length(Real h_inv_i, Real h_inv_j) {
  return std::min(h_inv_i, h_inv_j);
}

// GADGET-2's TreePM split of the Newtonian pair force (docs/gravity.md, "Periodic TreePM"):
// the periodic mesh computes the long-range part, the tree (or a direct sum) the short-range
// part, which is the Newtonian (or softened) pair force times force_factor(r) and the potential
// times potential_factor(r), with u = r / (2 r_s):
//   potential_factor = erfc(u),   force_factor = erfc(u) + (2 u / sqrt(pi)) exp(-u^2).
// Both fall below 0.02 at cutoff_radius() = 4.5 r_s, beyond which the short range is dropped.
// r_s = 0 means no split: isolated runs, where the tree computes the whole force.
struct GravitySplit {
  double r_s = 0.0;
  double cutoff_factor = 4.5;  // r_cut / r_s

  bool enabled() const { return r_s > 0.0; }
  double force_factor(double r) const {
    const double u = r / (2.0 * r_s);
    return std::erfc(u) + (2.0 / std::sqrt(std::numbers::pi)) * u * std::exp(-u * u);
  }
  double potential_factor(double r) const { return std::erfc(r / (2.0 * r_s)); }
  // The factors of the second and third radial derivatives (1/r d/dr)^n of erfc(u)/r against
  // the Newtonian ones, erfc(u) + exp(-u^2) Q_n(u) / sqrt(pi) with Q_2 = 2u + 4u^3/3 and
  // Q_3 = Q_2 + 8u^5/15, for a node's quadrupole term (force_factor is n = 1).
  double second_derivative_factor(double r) const {
    const double u = r / (2.0 * r_s), u2 = u * u;
    return std::erfc(u) + std::exp(-u2) * u * (2.0 + 4.0 / 3.0 * u2) / std::sqrt(std::numbers::pi);
  }
  double third_derivative_factor(double r) const {
    const double u = r / (2.0 * r_s), u2 = u * u;
    return std::erfc(u) + std::exp(-u2) * u * (2.0 + u2 * (4.0 / 3.0 + 8.0 / 15.0 * u2)) / std::sqrt(std::numbers::pi);
  }
  double cutoff_radius() const { return enabled() ? cutoff_factor * r_s : std::numeric_limits<double>::infinity(); }
};

// Per unit G m of the source: acceleration = -G m dx force, potential = G m potential,
// with dx = x_target - x_source.
struct PairGravity {
  double force;      // g(r): 1/r^3 beyond the spline length
  double potential;  // -1/r beyond the spline length
};

// GADGET-2's piecewise polynomials (forcetree.c), written with the exact fractions whose
// decimal forms GADGET-2 prints (32/3 for 10.666666666667 and so on), so the pieces join
// to round-off at u = 1/2 and u = 1. The Newtonian piece is 1/r^3 as r_inv^3: divisions
// and square roots are what the vectorised near loop waits on.
inline PairGravity softened_pair(double r, double h, const GravitySplit& split = GravitySplit{}) {
  PairGravity out;
  if (r >= h) {
    const double r_inv = 1.0 / r;
    out.force = r_inv * r_inv * r_inv;
    out.potential = -r_inv;
  } else {
    const double h_inv = 1.0 / h;
    const double h_inv3 = h_inv * h_inv * h_inv;
    const double u = r * h_inv;
    const double u2 = u * u;
    if (u < 0.5) {
      out.force = h_inv3 * (32.0 / 3.0 + u2 * (32.0 * u - 192.0 / 5.0));
      out.potential = h_inv * (-14.0 / 5.0 + u2 * (16.0 / 3.0 + u2 * (32.0 / 5.0 * u - 48.0 / 5.0)));
    } else {
      // 1/u = h/r: one division (shared with the Newtonian piece in the branch-free form).
      const double u_inv = h * (1.0 / r);
      out.force = h_inv3 * (64.0 / 3.0 - 48.0 * u + 192.0 / 5.0 * u2 - 32.0 / 3.0 * u2 * u -
                            1.0 / 15.0 * (u_inv * u_inv * u_inv));
      out.potential = h_inv * (-16.0 / 5.0 + 1.0 / 15.0 * u_inv +
                               u2 * (32.0 / 3.0 + u * (-16.0 + u * (48.0 / 5.0 - 32.0 / 15.0 * u))));
    }
  }
  if (split.enabled()) {
    out.force *= split.force_factor(r);
    out.potential *= split.potential_factor(r);
  }
  return out;
}

// softened_pair with every piece computed and the right one selected: in double, the same
// arithmetic operation by operation, so the same bits, but without branches, so that a loop
// over targets calling it vectorises (the pieces not selected may be infinite; they are
// dropped). The tree's near loop runs it in float (twice the lanes; docs/gravity.md).
// h_inv must be 1 / h exactly (pair_inverse_spline_length gives it without a division).
template <class Real>
struct PairGravityOf {
  Real force, potential;
};
template <class Real>
inline PairGravityOf<Real> softened_pair_branch_free(Real r, Real h, Real h_inv) {
  const Real r_inv = Real(1) / r;
  const Real newton_force = r_inv * r_inv * r_inv, newton_potential = -r_inv;
  const Real h_inv3 = h_inv * h_inv * h_inv;
  const Real u = r * h_inv;
  const Real u2 = u * u;
  const Real inner_force = h_inv3 * (Real(32.0 / 3.0) + u2 * (Real(32.0) * u - Real(192.0 / 5.0)));
  const Real inner_potential =
      h_inv * (Real(-14.0 / 5.0) + u2 * (Real(16.0 / 3.0) + u2 * (Real(32.0 / 5.0) * u - Real(48.0 / 5.0))));
  const Real u_inv = h * r_inv;
  const Real outer_force = h_inv3 * (Real(64.0 / 3.0) - Real(48.0) * u + Real(192.0 / 5.0) * u2 -
                                     Real(32.0 / 3.0) * u2 * u - Real(1.0 / 15.0) * (u_inv * u_inv * u_inv));
  const Real outer_potential =
      h_inv * (Real(-16.0 / 5.0) + Real(1.0 / 15.0) * u_inv +
               u2 * (Real(32.0 / 3.0) + u * (Real(-16.0) + u * (Real(48.0 / 5.0) - Real(32.0 / 15.0) * u))));
  // One select per comparison (nested selects on two comparisons stop GCC vectorising).
  const Real spline_force = u < Real(0.5) ? inner_force : outer_force;
  const Real spline_potential = u < Real(0.5) ? inner_potential : outer_potential;
  PairGravityOf<Real> out;
  out.force = r >= h ? newton_force : spline_force;
  out.potential = r >= h ? newton_potential : spline_potential;
  return out;
}

// The softened potential p(r) of a unit mass (p = -1/r beyond h) and its radial derivatives
// as a multipole expansion needs them: d1 = p'/r (the pair force above), d2 = d1'/r,
// d3 = d2'/r. Then the Hessian of p is d2 x x^T + d1 I and its third derivatives are
// d3 x_i x_j x_k + d2 (x_i d_jk + x_j d_ik + x_k d_ij). Newtonian: d1 = 1/r^3, d2 = -3/r^5,
// d3 = 15/r^7. On the spline's pieces (u = r/h):
//   u < 1/2:     d2 = (-384/5 + 96 u) / h^5,                  d3 = 96 / (h^6 r)
//   1/2 <= u < 1: d2 = (1/(5 u^5) - 48/u + 384/5 - 32 u) / h^5, d3 = (-1/u^7 + 48/u^3 - 32/u) / h^7
// Each is continuous where the pieces meet (GravityKernel.SoftenedDerivativesAreTheKernels).
// Branch-free like softened_pair_branch_free, whose potential and d1 it returns bit for bit.
template <class Real>
struct SoftenedDerivativesOf {
  Real potential, d1, d2, d3;
};
template <class Real>
inline SoftenedDerivativesOf<Real> softened_derivatives_branch_free(Real r, Real h, Real h_inv) {
  const PairGravityOf<Real> pair = softened_pair_branch_free(r, h, h_inv);
  const Real r_inv = Real(1) / r;
  const Real r2_inv = r_inv * r_inv;
  const Real newton_d2 = Real(-3) * (r2_inv * r2_inv * r_inv);
  const Real newton_d3 = Real(15) * (r2_inv * r2_inv * r2_inv * r_inv);
  const Real h_inv2 = h_inv * h_inv;
  const Real h_inv5 = h_inv2 * h_inv2 * h_inv;
  const Real h_inv6 = h_inv5 * h_inv;
  const Real u = r * h_inv;
  const Real inner_d2 = h_inv5 * (Real(-384.0 / 5.0) + Real(96) * u);
  const Real inner_d3 = Real(96) * h_inv6 * r_inv;
  const Real u_inv = h * r_inv;
  const Real u_inv2 = u_inv * u_inv;
  const Real u_inv3 = u_inv2 * u_inv;
  const Real outer_d2 = h_inv5 * (Real(0.2) * (u_inv3 * u_inv2) - Real(48) * u_inv + Real(384.0 / 5.0) - Real(32) * u);
  const Real outer_d3 = h_inv6 * h_inv * (u_inv * (Real(-1) * (u_inv3 * u_inv3) + Real(48) * u_inv2 - Real(32)));
  const Real spline_d2 = u < Real(0.5) ? inner_d2 : outer_d2;
  const Real spline_d3 = u < Real(0.5) ? inner_d3 : outer_d3;
  SoftenedDerivativesOf<Real> out;
  out.potential = pair.potential;
  out.d1 = pair.force;
  out.d2 = r >= h ? newton_d2 : spline_d2;
  out.d3 = r >= h ? newton_d3 : spline_d3;
  return out;
}

}  // namespace fountain::gravity
