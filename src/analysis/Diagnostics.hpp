// The paper's time-series diagnostics (docs/physics.md section 7): gas phases, energies, momenta, unbound gas.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/ExactSum.hpp"
#include "core/IdealGas.hpp"
#include "core/Units.hpp"
#include "core/Vec3.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"

namespace fountain::analysis {

// The phases of the paper's figures and time series (its section 3.2): hot T > 2 T*; cold
// T <= 2 T* and rho > 0.1 rho*; warm otherwise. (Feedback's cold phase, T < 2 T*, is
// feedback's own: feedback/FeedbackLaw.hpp.)
struct FigurePhases {
  double t_star_k = 4.0e4;           // T*
  double rho_star_internal = 0.0;    // rho* = 5e-26 g cm^-3 in internal density units (physical)

  static FigurePhases paper(const Units& units) { return {4.0e4, 5.0e-26 / units.density_cgs()}; }
  bool hot(double t) const { return t > 2.0 * t_star_k; }
  bool cold(double t, double rho) const { return t <= 2.0 * t_star_k && rho > 0.1 * rho_star_internal; }
};

struct Diagnostics {
  double mass_gas = 0.0, mass_dark_matter = 0.0;
  double mass_hot = 0.0, mass_warm = 0.0, mass_cold = 0.0;
  double mass_unbound = 0.0;         // gas with v^2/2 + potential > 0
  double thermal = 0.0, kinetic = 0.0, potential = 0.0;
  double radiated = 0.0;             // by cooling since the start: total_energy + radiated is conserved
  // Star formation and feedback. The engine's tallies (since the start) are filled in by
  // the caller; the rest is measured on the particles.
  double mass_stars = 0.0;           // star particles
  double mass_stars_hidden = 0.0;    // hidden in gas particles
  double mass_promoted_diffuse = 0.0;  // gas promoted by feedback and not cold now (the paper's Fig 4)
  double reservoir = 0.0;            // feedback energy held in reservoirs
  double sfr_msun_per_yr = 0.0;      // mean since the previous line
  double feedback_own = 0.0, feedback_reservoir = 0.0, feedback_hot = 0.0;  // injected, since the start
  double thermal_locked = 0.0;       // thermal energy of gas turned into stars, since the start
  long long promotions = 0;          // into the hot phase, since the start: with mass_promoted_diffuse
                                     // it tells how long promoted gas stays out of the cold phase
  // Resolution now: the smallest gas smoothing length, and the smallest time bin of any
  // particle with the step it stands for (the latter filled in by the caller, who has the
  // timeline): how close a run is to its floors of h and dt.
  double h_min_gas = 0.0;
  int time_bin_min = 0;
  double dt_min = 0.0;
  Vec3 momentum, angular_momentum;   // about the origin
  double total_energy() const { return thermal + kinetic + potential; }
};

// The same sums taken over the particles a run at a time: each call sums its run in doubles,
// in the run's order, and adds those sums exactly to the totals (core/ExactSum.hpp), which
// combine exactly with other parts' (add(), another rank's by add_packed()). So the result
// depends on the runs alone (the leaves, which are the same on any number of ranks or
// threads), not on their order or on who summed them; runs of one particle give the exact
// total. The state is summed as it stands (gas at its predicted values; potentials from the
// last force computation, zero without gravity); a comoving run's (scale factor a < 1 or not,
// gamma = 5/3) is measured physically: rho'/a^3, u'/a^2, h = a h', peculiar velocities v'/a
// and potentials Phi'/a; plain runs pass a = 1.
class DiagnosticsSum {
 public:
  DiagnosticsSum(TemperatureOf temperature, const FigurePhases& phases, double a = 1.0);
  void add_gas(const GasParticles& gas, std::size_t first, std::size_t count);
  void add_collisionless(const CollisionlessParticles& p, std::size_t first, std::size_t count);
  // Another rank's sums (from pack()) or another part's.
  void add(const DiagnosticsSum& other);
  std::vector<char> pack() const;
  void add_packed(std::span<const char> packed);
  Diagnostics result() const;

 private:
  enum Sum {
    kMassGas, kMassDarkMatter, kMassHot, kMassWarm, kMassCold, kMassUnbound, kThermal, kKinetic, kPotential,
    kMassStars, kMassStarsHidden, kMassPromotedDiffuse, kReservoir, kMomentum, kAngularMomentum = kMomentum + 3,
    kSums = kAngularMomentum + 3
  };
  static void add_vector(std::array<double, kSums>& part, Sum s, const Vec3& v) {
    for (int k = 0; k < 3; ++k) part[static_cast<std::size_t>(s + k)] += v[k];
  }
  void add_part(const std::array<double, kSums>& part);

  TemperatureOf temperature_;
  FigurePhases phases_;
  double a_;
  std::array<ExactSum, kSums> sums_;
  double h_min_;
  int bin_min_;
  std::uint64_t gas_ = 0, collisionless_ = 0;
};

}  // namespace fountain::analysis
