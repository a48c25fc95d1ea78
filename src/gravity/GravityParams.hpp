// Self-gravity settings of a run: softenings per species, force accuracy and the timestep criterion.
#pragma once
#include <algorithm>
#include <cmath>

#include "gravity/GravityTree.hpp"
#include "particles/CollisionlessParticles.hpp"

namespace fountain {

class ParameterFile;
struct Units;

struct GravityParams {
  bool enabled = false;
  double G = 1.0;                      // Newton's constant in internal units
  // Plummer-equivalent softenings (the spline reaches 2.8 eps). The paper: gas = half the
  // dark matter's, stars (hybrid particles' spawn) the mean of the two.
  double softening_dark_matter = 0.0;
  double softening_gas = 0.0;
  double alpha_force = 0.01;           // relative opening criterion
  double theta = 0.5;                  // Barnes-Hut angle of the first force computation
  gravity::OpeningCriterion criterion = gravity::OpeningCriterion::gadget2_monopole;
  double eta = 0.08;                   // dt_grav = sqrt(2 eta eps / |a|)
  // Periodic boxes (TreePM): mesh cells per side (0: chosen from the particle count) and the
  // split scale r_s in mesh cells.
  int mesh_cells = 0;
  double split_cells = 1.25;

  // Comoving runs: the dark matter's largest physical softening (0: none); every softening
  // then takes the factor min(1, softening_max_physical / (a softening_dark_matter)).
  double softening_max_physical = 0.0;
  // The high-resolution dark matter's particle mass (set by the engine from the particles):
  // low-resolution particles of mass m soften over softening_dark_matter (m / it)^(1/3).
  double low_res_reference_mass = 0.0;

  double softening_stars() const { return 0.5 * (softening_gas + softening_dark_matter); }
  double softening(Species s, double mass) const {
    if (s == Species::Star) return softening_stars();
    if (s == Species::LowResDarkMatter && low_res_reference_mass > 0.0)
      return softening_dark_matter * std::cbrt(mass / low_res_reference_mass);
    return softening_dark_matter;
  }
  // The factor on every (comoving) softening at scale factor a.
  double softening_factor(double a) const {
    return softening_max_physical > 0.0 ? std::min(1.0, softening_max_physical / (a * softening_dark_matter)) : 1.0;
  }
  gravity::WalkConfig walk() const {
    gravity::WalkConfig w;
    w.G = G;
    w.alpha_force = alpha_force;
    w.theta = theta;
    w.criterion = criterion;
    return w;
  }

  static GravityParams from(const ParameterFile& p, const Units& units);
};

}  // namespace fountain
