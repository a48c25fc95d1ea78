// Self-gravity settings of a run: softenings per species, force accuracy and the timestep criterion.
#pragma once
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

  double softening_stars() const { return 0.5 * (softening_gas + softening_dark_matter); }
  double softening(Species s) const { return s == Species::Star ? softening_stars() : softening_dark_matter; }
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
