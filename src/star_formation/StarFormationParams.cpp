#include "star_formation/StarFormationParams.hpp"

#include <fmt/format.h>

#include "core/Error.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

StarFormationParams StarFormationParams::from(const ParameterFile& p) {
  StarFormationParams s;
  s.enabled = p.flag("star_formation.enabled");
  s.efficiency = p.real("star_formation.efficiency");
  s.density_threshold_cgs = p.real("star_formation.density_threshold_cgs");
  s.temperature_threshold = p.real("star_formation.temperature_threshold");
  s.spawn_fraction = p.real("star_formation.spawn_fraction");
  s.dissolve_fraction = p.real("star_formation.dissolve_fraction");
  if (s.dissolve_fraction >= 1.0 - s.spawn_fraction)
    throw InputError(fmt::format("{}: 'star_formation.dissolve_fraction' must be below 1 - 'star_formation.spawn_fraction'",
                                 p.origin()));
  return s;
}

}  // namespace fountain
