// GADGET-2's cubic-spline softened gravity between two point masses, and the TreePM split hook.
#pragma once
#include <algorithm>
#include <limits>

namespace fountain::gravity {

// Softening lengths are given as the Plummer-equivalent eps everywhere (that is what
// PHYSICS.md and the parameter files quote); the spline reaches Newtonian at h = 2.8 eps.
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

// The hook for a TreePM short-range force. Today it is the identity: the tree computes the
// whole force. TreePM will multiply the softened pair force by
// erfc(r / 2 r_s) + (r / r_s sqrt(pi)) exp(-r^2 / 4 r_s^2) and the potential by
// erfc(r / 2 r_s) (GADGET-2's `shortrange_table`, tabulated there in u = r / 2 r_s), and
// the walk will skip nodes farther than cutoff_radius() (GADGET-2: RCUT = 4.5 r_s), whose
// contribution then comes entirely from the PM mesh. Callers already pass a GravitySplit
// and ask it for both factors, so enabling it changes this struct only.
struct GravitySplit {
  constexpr bool enabled() const { return false; }
  constexpr double force_factor(double /*r*/) const { return 1.0; }
  constexpr double potential_factor(double /*r*/) const { return 1.0; }
  constexpr double cutoff_radius() const { return std::numeric_limits<double>::infinity(); }
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

}  // namespace fountain::gravity
