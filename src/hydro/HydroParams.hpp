// The SPH and MSPH parameters the interaction kernels need, read once from the parameter file.
#pragma once

namespace fountain {

class ParameterFile;

// syw: the paper's criterion (GADGET-1 form); signal_velocity: GADGET-2's and SWIFT's.
enum class CourantCriterion { Syw, SignalVelocity };

struct HydroParams {
  double gamma = 5.0 / 3.0;
  double neighbours = 32.0;
  double neighbours_tolerance = 1.0;
  double sph_alpha = 1.5;
  double viscosity_alpha = 1.3;
  // The viscosity sees each pair's velocities reconstructed to the pair's midpoint along
  // their gradients, with a slope limiter: none in smooth flows, all of it in shocks.
  bool viscosity_reconstruction = false;
  double courant = 0.1;
  CourantCriterion courant_criterion = CourantCriterion::Syw;
  bool msph = true;
  double msph_A = 10.0;
  double msph_A_prime = 10.0;
  double h_max = 0.0;  // 0: unlimited
  // Floor of h (internal length): hydro.h_min_ratio times the gas's spline softening length
  // 2.8 eps_gas, as GADGET (the paper's code) sets it from MinGasHsmlFractional, so that a cold
  // clump cannot shrink its kernel far below the scale on which its self-gravity is resolved.
  // 0: none.
  double h_min = 0.0;
  int max_h_iterations = 50;
  bool timestep_limiter = true;  // no particle's step more than 2^limiter_bins x a neighbour's
  int limiter_bins = 2;

  static HydroParams from(const ParameterFile& p);
};

}  // namespace fountain
