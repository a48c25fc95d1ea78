// The field of one tree node's multipole expansion (monopole, or monopole + quadrupole), used by the walk and tested alone.
#pragma once
#include <array>
#include <cmath>

#include "core/Vec3.hpp"
#include "gravity/GravityKernel.hpp"

namespace fountain::gravity {

// How many terms of a node's expansion about its centre of mass the walk uses. There is no
// dipole term: about the centre of mass it vanishes. The neglected remainder is of relative
// size (l/r)^2 for `monopole` and (l/r)^3 for `quadrupole` (l the node's size, r the
// distance); tests/test_gravity.cpp (GravityMultipole.*) measures both slopes.
enum class MultipoleOrder { monopole, quadrupole };

// The traceless quadrupole Q = sum m (3 s s^T - |s|^2 I), s = x - com, stored as
// xx, yy, zz, xy, xz, yz (TreeNode::quadrupole).
using Quadrupole = std::array<double, 6>;

struct NodeField {
  Vec3 acceleration;
  double potential = 0.0;
};

// Newtonian field at d = x_target - com of a node of mass M and quadrupole Q:
//   phi = -G (M / r + d.Q.d / (2 r^5))
//   a   = -grad phi = G (-M d / r^3 + Q d / r^5 - (5/2) (d.Q.d) d / r^7).
// With a GravitySplit enabled only the monopole is scaled by the short-range factors
// (GADGET-2's monopole-only form); the tree walk's TreePM evaluation
// (GravityWalkShortRange.cpp) scales the quadrupole term's derivatives as well and keeps the
// trace term the truncated potential needs.
inline NodeField node_field(const Vec3& d, double mass, const Quadrupole& q, double G, MultipoleOrder order,
                            const GravitySplit& split = GravitySplit{}) {
  const double r2 = dot(d, d);
  const double r = std::sqrt(r2);
  const double r_inv = 1.0 / r;
  const double r2_inv = r_inv * r_inv;
  const double r3_inv = r_inv * r2_inv;
  const double split_f = split.enabled() ? split.force_factor(r) : 1.0;
  const double split_p = split.enabled() ? split.potential_factor(r) : 1.0;
  NodeField out;
  out.acceleration = (-G * split_f * mass * r3_inv) * d;
  out.potential = -G * split_p * mass * r_inv;
  if (order == MultipoleOrder::quadrupole) {
    const double r5_inv = r3_inv * r2_inv;
    const Vec3 qd{q[0] * d.x + q[3] * d.y + q[4] * d.z, q[3] * d.x + q[1] * d.y + q[5] * d.z,
                  q[4] * d.x + q[5] * d.y + q[2] * d.z};
    const double dqd = dot(d, qd);
    out.acceleration += G * r5_inv * (qd + (-2.5 * dqd * r2_inv) * d);
    out.potential -= G * 0.5 * dqd * r5_inv;
  }
  return out;
}

// The same expansion with the softened potential p of pair spline length h (softened_pair's;
// Newtonian beyond h), for a node that lies within some target's softening. With
// d1, d2, d3 the radial derivatives of softened_derivatives_branch_free and
// T = sum m |s|^2 (TreeNode::second_moment), the Taylor terms of sum m p(|d - s|) about the
// centre of mass are
//   phi = G (M p + d2 (d.Q.d) / 6 + T (d2 r^2 / 6 + d1 / 2))
//   a   = -G ((M d1 + T (d3 r^2 / 6 + 5 d2 / 6) + d3 (d.Q.d) / 6) d + (d2 / 3) Q d).
// The T terms vanish for the Newtonian potential (its Laplacian is zero), which is why the
// traceless Q suffices there; inside the softening they do not. Beyond h this is node_field's
// quadrupole expansion up to rounding.
inline NodeField softened_node_field(const Vec3& d, double mass, const Quadrupole& q, double trace, double h,
                                     double G) {
  const double r2 = dot(d, d);
  const auto k = softened_derivatives_branch_free(std::sqrt(r2), h, 1.0 / h);
  const Vec3 qd{q[0] * d.x + q[3] * d.y + q[4] * d.z, q[3] * d.x + q[1] * d.y + q[5] * d.z,
                q[4] * d.x + q[5] * d.y + q[2] * d.z};
  const double dqd = dot(d, qd);
  NodeField out;
  const double along = mass * k.d1 + trace * (k.d3 * r2 / 6.0 + 5.0 * k.d2 / 6.0) + k.d3 * dqd / 6.0;
  out.acceleration = -G * (along * d + (k.d2 / 3.0) * qd);
  out.potential = G * (mass * k.potential + k.d2 * dqd / 6.0 + trace * (k.d2 * r2 / 6.0 + 0.5 * k.d1));
  return out;
}

}  // namespace fountain::gravity
