// The root finder of the smoothing length: N(h) = N_ngb by Newton steps kept inside a bracket.
#pragma once
#include <cmath>

#include "hydro/HydroIact.hpp"
#include "hydro/HydroParams.hpp"

namespace fountain::hydro {

struct SmoothingLengthSolve {
  double h = 0.0;
  DensityResult density;  // at h when converged, else at the last h tried
  bool converged = false;
  double lo = 0.0, hi = 0.0;  // the bracket it ended with
};

// Solves |N(h) - N_ngb| <= tolerance for h in (0, hi], starting from h (taken as hi / 2 when
// outside), with `density_at(h)` giving the density sums' result at h. Newton steps are taken
// where they stay inside the bracket, else the bracket is halved; after kPlainNewtonSteps the
// bracket is also halved wherever Newton shrinks it more slowly than halving would. N(h) is
// S-shaped for a particle at the edge of a tight clump, and plain Newton then jumps between
// the bracket's two ends without end.
inline constexpr int kPlainNewtonSteps = 20;

template <class DensityAt>
SmoothingLengthSolve solve_smoothing_length(DensityAt&& density_at, double h, double hi, const HydroParams& p) {
  SmoothingLengthSolve s;
  s.hi = hi;
  if (!(h > 0.0 && h < hi)) h = 0.5 * hi;
  double step = hi, step_before = hi;
  for (int it = 0; it < p.max_h_iterations; ++it) {
    s.density = density_at(h);
    s.h = h;
    const double f = s.density.wcount - p.neighbours;
    if (std::fabs(f) <= p.neighbours_tolerance) {
      s.converged = true;
      return s;
    }
    (f < 0.0 ? s.lo : s.hi) = h;
    const double slope = s.density.wcount_dh;
    const double newton = slope > 0.0 ? h - f / slope : -1.0;
    // The guard against slow shrinking comes in only after kPlainNewtonSteps: where Newton
    // converges, h then comes out exactly as it always did (and runs keep their results).
    const bool slow = it >= kPlainNewtonSteps && std::fabs(2.0 * f) > std::fabs(step_before * slope);
    const bool bisect = !(newton > s.lo && newton < s.hi) || slow;
    step_before = step;
    const double next = bisect ? 0.5 * (s.lo + s.hi) : newton;
    step = std::fabs(next - h);
    h = next;
  }
  return s;
}

}  // namespace fountain::hydro
