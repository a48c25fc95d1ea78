#include "gravity/GravityParams.hpp"

#include <fmt/format.h>

#include "core/Error.hpp"
#include "core/Units.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

GravityParams GravityParams::from(const ParameterFile& p, const Units& units) {
  GravityParams g;
  g.enabled = p.flag("gravity.enabled");
  const double G = p.real("gravity.G");
  g.G = G > 0.0 ? G : units.gravitational_constant();
  g.softening_dark_matter = p.real("gravity.softening_dark_matter");
  g.softening_gas = p.real("gravity.softening_gas");
  if (g.softening_gas == 0.0) g.softening_gas = 0.5 * g.softening_dark_matter;
  if (g.enabled && !(g.softening_gas > 0.0))
    throw InputError(fmt::format("{}: gravity is on but neither 'gravity.softening_gas' nor "
                                 "'gravity.softening_dark_matter' is set (> 0)",
                                 p.origin()));
  g.softening_max_physical = p.real("gravity.softening_max_physical");
  if (g.softening_max_physical > 0.0 && !(g.softening_dark_matter > 0.0))
    throw InputError(fmt::format("{} = {} needs gravity.softening_dark_matter, to which it is the physical limit",
                                 p.where("gravity.softening_max_physical"), g.softening_max_physical));
  if (g.softening_max_physical > 0.0 && !p.flag("cosmology.enabled"))
    throw InputError(fmt::format("{} is for comoving runs (a plain run's softenings are physical already)",
                                 p.where("gravity.softening_max_physical")));
  g.alpha_force = p.real("gravity.alpha_force");
  g.eta = p.real("gravity.eta");
  g.mesh_cells = static_cast<int>(p.integer("gravity.mesh_cells"));
  if (g.mesh_cells != 0 && (g.mesh_cells < 16 || g.mesh_cells % 2 != 0))
    throw InputError(fmt::format("{}: 'gravity.mesh_cells' = {}: the mesh needs an even number of cells, at least 16 "
                                 "(or 0 to choose it from the particle count)",
                                 p.origin(), g.mesh_cells));
  g.split_cells = p.real("gravity.split_cells");
  g.criterion = p.text("gravity.opening_criterion") == "quadrupole" ? gravity::OpeningCriterion::relative_quadrupole
                                                                    : gravity::OpeningCriterion::gadget2_monopole;
  return g;
}

}  // namespace fountain
