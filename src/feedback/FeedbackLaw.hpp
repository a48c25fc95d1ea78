// The multiphase feedback rules as pure functions: the energy split, the cold phase, the promotion temperature (docs/physics.md, feedback).
#pragma once
#include <algorithm>

namespace fountain::feedback {

// Supernova energy e_sn dM split among the three channels.
struct FeedbackShares {
  double own = 0.0;        // 1 - eps_c - eps_h: the particle's own thermal energy
  double reservoir = 0.0;  // eps_c
  double hot = 0.0;        // eps_h: the nearest hot neighbours
};

inline FeedbackShares split_feedback(double energy, double eps_cold, double eps_hot) {
  FeedbackShares s;
  s.reservoir = eps_cold * energy;
  s.hot = eps_hot * energy;
  s.own = energy - s.reservoir - s.hot;
  return s;
}

// Feedback's cold phase (the paper's section 2.3): rho > 0.1 rho* and T < 2 T*; everything
// else is hot, and takes eps_h. (The figures' phases, T <= 2 T*, are analysis's.) Tested on u
// rather than T: T(u) is monotonic, so T < 2 T* is u below the energy of 2 T*, and the
// searches need no temperature solve per candidate.
struct FeedbackColdPhase {
  double rho_min = 0.0;  // 0.1 rho*, internal units
  double u_max = 0.0;    // u of 2 T*

  bool contains(double rho, double u) const { return rho > rho_min && u < u_max; }
};

// The paper's rule (its section 2.3): T_prom = factor T*, unless the mean T of the hot
// neighbours is higher than that, when it is hot_factor x their mean. (Not the larger of the
// two: for a mean between factor T* / hot_factor and factor T* the threshold stays factor T*.)
// mean_hot < 0: none found.
inline double promotion_temperature(double t_star, double factor, double hot_factor, double mean_hot) {
  const double base = factor * t_star;
  return mean_hot > base ? hot_factor * mean_hot : base;
}

}  // namespace fountain::feedback
