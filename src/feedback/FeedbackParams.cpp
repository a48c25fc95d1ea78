#include "feedback/FeedbackParams.hpp"

#include <fmt/format.h>

#include "core/Error.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

FeedbackParams FeedbackParams::from(const ParameterFile& p) {
  FeedbackParams f;
  f.energy_per_solar_mass_erg = p.real("feedback.energy_per_solar_mass");
  f.eps_cold = p.real("feedback.eps_cold");
  f.eps_hot = p.real("feedback.eps_hot");
  f.hot_neighbours = static_cast<int>(p.integer("feedback.hot_neighbours"));
  f.max_search_radius = p.real("feedback.max_search_radius");
  f.promotion_factor = p.real("feedback.promotion_factor");
  f.promotion_hot_factor = p.real("feedback.promotion_hot_factor");
  if (f.eps_cold + f.eps_hot > 1.0)
    throw InputError(fmt::format("{}: 'feedback.eps_cold' + 'feedback.eps_hot' = {} exceeds 1", p.origin(),
                                 f.eps_cold + f.eps_hot));
  return f;
}

}  // namespace fountain
