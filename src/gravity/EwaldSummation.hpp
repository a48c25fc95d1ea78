// Exact periodic gravity by Ewald summation: the reference the TreePM force is tested against.
#pragma once
#include <span>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::gravity {

// How the Ewald sums are cut. The real-space sum keeps every image within real_reach of the
// point, the Fourier sum every wave vector 2 pi h / L with |h|^2 <= fourier_h2; alpha is the
// splitting in units of 1/L. Both neglected tails fall as exp(-x^2): the defaults leave terms
// below 1e-16 of the leading one (the sums converge to round-off, whatever alpha, as the tests
// check).
struct EwaldSettings {
  double alpha = 2.0;        // in 1/L
  double real_reach = 2.9;   // in L: erfc(alpha r) < 1e-16 beyond it for alpha = 2
  int fourier_h2 = 36;       // exp(-pi^2 h^2 / alpha^2) < 1e-38 beyond it for alpha = 2
};

// The field of a unit mass (G = 1) at the origin of a periodic box of side L, with a uniform
// neutralising background, at x: acceleration and potential (the potential's zero is Ewald's,
// the mean over the box).
struct EwaldField {
  Vec3 acceleration;
  double potential = 0.0;
};
EwaldField ewald_field(const Vec3& x, double box, const EwaldSettings& settings = {});

// What the periodic images and the background add to the nearest image's Newtonian field:
// ewald_field(x) + x_n / |x_n|^3 and ewald_field(x) + 1 / |x_n|, x_n the nearest image of x.
// Smooth everywhere, finite at x = 0 (acceleration 0, potential 2.8372975 / L).
EwaldField ewald_correction(const Vec3& x, double box, const EwaldSettings& settings = {});

// Exact periodic accelerations of chosen targets among a set of point masses: each other
// particle's softened nearest-image force (softened_pair, pair softening as the tree's) plus
// its ewald_correction. O(targets x sources) in real space; the Fourier sum goes through the
// set's structure factors, O((targets + sources) x waves).
std::vector<Vec3> ewald_accelerations(std::span<const Vec3> positions, std::span<const double> masses,
                                      std::span<const double> softenings, double box, double G,
                                      std::span<const std::size_t> targets);

}  // namespace fountain::gravity
