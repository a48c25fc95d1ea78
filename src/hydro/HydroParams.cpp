#include "hydro/HydroParams.hpp"

#include <fmt/format.h>

#include "core/Error.hpp"
#include "gravity/GravityKernel.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

HydroParams HydroParams::from(const ParameterFile& p) {
  HydroParams h;
  h.gamma = p.real("hydro.gamma");
  h.neighbours = p.real("hydro.neighbours");
  h.neighbours_tolerance = p.real("hydro.neighbours_tolerance");
  h.sph_alpha = p.real("hydro.sph_alpha");
  h.viscosity_alpha = p.real("hydro.viscosity_alpha");
  h.viscosity_reconstruction = p.flag("hydro.viscosity_reconstruction");
  h.courant = p.real("hydro.courant");
  h.courant_criterion = p.text("time_integration.courant_criterion") == "signal_velocity"
                            ? CourantCriterion::SignalVelocity
                            : CourantCriterion::Syw;
  h.msph = p.flag("hydro.msph");
  h.msph_A = p.real("hydro.msph_A");
  h.msph_A_prime = p.real("hydro.msph_A_prime");
  h.h_max = p.real("hydro.h_max");
  const double ratio = p.real("hydro.h_min_ratio");
  if (ratio > 0.0) {
    double eps_gas = p.real("gravity.softening_gas");
    if (eps_gas == 0.0) eps_gas = 0.5 * p.real("gravity.softening_dark_matter");
    if (!(eps_gas > 0.0))
      throw InputError(fmt::format("{}: key 'hydro.h_min_ratio' = {} needs a gas softening, but neither "
                                   "'gravity.softening_gas' nor 'gravity.softening_dark_matter' is set",
                                   p.origin(), ratio));
    // GADGET's MinGasHsmlFractional counts in the gas's spline softening length (where its force
    // turns Newtonian), not in the Plummer-equivalent epsilon the parameter file quotes.
    h.h_min = ratio * gravity::spline_length(eps_gas);
    if (h.h_max > 0.0 && h.h_min > h.h_max)
      throw InputError(fmt::format("{}: the smallest smoothing length hydro.h_min_ratio x 2.8 x softening = {} exceeds "
                                   "'hydro.h_max' = {}",
                                   p.origin(), h.h_min, h.h_max));
  }
  h.max_h_iterations = static_cast<int>(p.integer("hydro.max_h_iterations"));
  h.timestep_limiter = p.flag("time_integration.timestep_limiter");
  h.limiter_bins = static_cast<int>(p.integer("time_integration.limiter_bin_difference"));
  return h;
}

}  // namespace fountain
