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
  s.energy_per_solar_mass_erg = p.real("feedback.energy_per_solar_mass");
  s.eps_cold = p.real("feedback.eps_cold");
  s.eps_hot = p.real("feedback.eps_hot");
  s.hot_neighbours = static_cast<int>(p.integer("feedback.hot_neighbours"));
  s.max_search_radius = p.real("feedback.max_search_radius");
  s.promotion_factor = p.real("feedback.promotion_factor");
  s.promotion_hot_factor = p.real("feedback.promotion_hot_factor");
  if (s.eps_cold + s.eps_hot > 1.0)
    throw InputError(fmt::format("{}: 'feedback.eps_cold' + 'feedback.eps_hot' = {} exceeds 1", p.origin(),
                                 s.eps_cold + s.eps_hot));
  if (s.dissolve_fraction >= 1.0 - s.spawn_fraction)
    throw InputError(fmt::format("{}: 'star_formation.dissolve_fraction' must be below 1 - 'star_formation.spawn_fraction'",
                                 p.origin()));
  return s;
}

}  // namespace fountain
