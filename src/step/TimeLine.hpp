// The integer timeline of individual power-of-two timesteps, and time bins.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "cosmology/IntegrationFactors.hpp"

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

// The integer timeline of a comoving run (docs/physics.md §9): the 2^56 ticks span ln a from
// ln a_begin to ln a_end, so steps in a bin are equal steps of ln a, and each factor of the
// comoving leapfrog over a tick interval is a difference of the expansion's tabulated
// integrals: consecutive intervals telescope. Ticks may be fractional (a step's midpoint,
// where its half kicks meet, for bin 0).
class ComovingTimeLine {
 public:
  explicit ComovingTimeLine(const cosmology::IntegrationFactors& factors)
      : factors_(&factors),
        ln_begin_(std::log(factors.a_begin())),
        tick_(std::log(factors.a_end() / factors.a_begin()) / static_cast<double>(TimeLine::ticks)) {}

  double ln_a(double tick) const { return ln_begin_ + tick * tick_; }
  double scale_factor(double tick) const { return std::exp(ln_a(tick)); }
  double ln_a_per_tick() const { return tick_; }
  double hubble(double tick) const { return factors_->background().hubble(scale_factor(tick)); }

  // x' += v' drift; v' += A'_g gravity_kick; v' += A'_h hydro_kick; u' += U' drift (the
  // energy equation's factor is the drift's); time: cosmic time.
  double drift(double t0, double t1) const { return between(cosmology::IntegrationFactors::drift, t0, t1); }
  double gravity_kick(double t0, double t1) const { return between(cosmology::IntegrationFactors::gravity_kick, t0, t1); }
  double hydro_kick(double t0, double t1) const { return between(cosmology::IntegrationFactors::hydro_kick, t0, t1); }
  double cosmic_time(double t0, double t1) const { return between(cosmology::IntegrationFactors::time, t0, t1); }

  // The largest bin whose step in ln a, at the expansion rate H(a) of tick ti, lasts at most a
  // physical time dt, and at most dln_a_max in ln a; -1 if dt is below one tick.
  int bin_for(double dt, IntegerTime ti, double dln_a_max) const {
    const double hubble = factors_->background().hubble(scale_factor(static_cast<double>(ti)));
    const double dln_a = std::min(hubble * dt, dln_a_max);
    const double ratio = dln_a / tick_;
    if (!(ratio >= 1.0)) return -1;
    int b = static_cast<int>(std::floor(std::log2(ratio)));
    if (b > TimeLine::max_bin) b = TimeLine::max_bin;
    while (b > 0 && std::ldexp(tick_, b) > dln_a) --b;
    return b;
  }

 private:
  double between(cosmology::IntegrationFactors::Kind k, double t0, double t1) const {
    return factors_->factor_between_ln(k, ln_a(t0), ln_a(t1));
  }
  const cosmology::IntegrationFactors* factors_;
  double ln_begin_, tick_;
};

}  // namespace fountain
