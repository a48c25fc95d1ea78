// The integer timeline of individual power-of-two timesteps, and time bins.
#pragma once
#include <cmath>
#include <cstdint>

namespace fountain {

using IntegerTime = std::int64_t;

// The run [t_begin, t_end] is cut into 2^max_bin integer ticks; a particle in bin b takes
// steps of 2^b ticks that start on multiples of 2^b, so all steps nest.
struct TimeLine {
  static constexpr int max_bin = 56;
  static constexpr IntegerTime ticks = IntegerTime{1} << max_bin;

  double t_begin = 0.0;
  double t_end = 1.0;

  double time_base() const { return (t_end - t_begin) / static_cast<double>(ticks); }
  double time(IntegerTime ti) const { return t_begin + static_cast<double>(ti) * time_base(); }
  static IntegerTime step_ticks(int bin) { return IntegerTime{1} << bin; }
  double step(int bin) const { return static_cast<double>(step_ticks(bin)) * time_base(); }

  // Whether a particle in `bin` ends (and starts) a step at ti.
  static bool active(int bin, IntegerTime ti) { return (ti & (step_ticks(bin) - 1)) == 0; }
  // The end of the step that contains ti for a particle in `bin`.
  static IntegerTime step_end(int bin, IntegerTime ti) { return (ti / step_ticks(bin) + 1) * step_ticks(bin); }

  // Largest bin whose step starts at ti (steps must stay aligned when they grow).
  static int largest_aligned_bin(IntegerTime ti) {
    if (ti == 0) return max_bin;
    int b = 0;
    while (b < max_bin && (ti & (IntegerTime{1} << b)) == 0) ++b;
    return b;
  }

  // Largest bin whose step does not exceed dt; -1 if dt is below one tick.
  int bin_for(double dt) const {
    const double ratio = dt / time_base();
    if (!(ratio >= 1.0)) return -1;
    int b = static_cast<int>(std::floor(std::log2(ratio)));
    if (b > max_bin) b = max_bin;
    while (b > 0 && step(b) > dt) --b;  // guard log2 rounding
    return b;
  }

  // Kick and drift factors: plain time intervals here; a comoving run replaces them by
  // the integrals of da/(a^2 H) and da/(a H) over the interval.
  double drift_factor(IntegerTime ti0, IntegerTime ti1) const { return static_cast<double>(ti1 - ti0) * time_base(); }
  double kick_factor(IntegerTime ti0, IntegerTime ti1) const { return static_cast<double>(ti1 - ti0) * time_base(); }
};

}  // namespace fountain
