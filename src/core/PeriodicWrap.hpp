// Folding a coordinate into a periodic box [0, L).
#pragma once
#include <cmath>

#include "core/Vec3.hpp"

namespace fountain {

// The image of x in [0, L). A tiny negative x folds to L in floating point (-2e-25 + 1 == 1):
// that is the box's own edge, so it becomes 0.
inline double wrap_into_box(double x, double L) {
  if (x >= 0.0 && x < L) return x;
  x -= L * std::floor(x / L);
  return x >= L || x < 0.0 ? 0.0 : x;
}

inline Vec3 wrap_into_box(const Vec3& x, const Vec3& box) {
  return {wrap_into_box(x.x, box.x), wrap_into_box(x.y, box.y), wrap_into_box(x.z, box.z)};
}

// b - a at the nearest periodic image in a cubic box of side L (plain b - a for L = 0).
inline Vec3 nearest_image(const Vec3& a, const Vec3& b, double L) {
  Vec3 d = b - a;
  if (L > 0.0)
    for (int k = 0; k < 3; ++k) {
      if (d[k] > 0.5 * L) d[k] -= L;
      else if (d[k] < -0.5 * L) d[k] += L;
    }
  return d;
}

}  // namespace fountain
