#include "engine/RunConfig.hpp"

#include <fmt/format.h>

#include "core/Error.hpp"
#include "params/ParameterFile.hpp"
#include "step/TimeLine.hpp"
#include "timestep/Integration.hpp"

namespace fountain {

RunConfig RunConfig::from(const ParameterFile& p) {
  RunConfig c;
  c.t_begin = p.real("run.t_begin");
  c.t_end = p.real("run.t_end");
  c.threads = static_cast<int>(p.integer("run.threads"));
  c.pin_threads = p.flag("run.pin_threads");
  c.max_steps = p.integer("run.max_steps");
  c.smoothing_length_guess = p.real("initial_conditions.smoothing_length_guess");
  c.hydro = HydroParams::from(p);
  c.integration.dt_min = p.real("time_integration.dt_min");
  c.integration.dt_max = p.real("time_integration.dt_max");
  if (c.integration.dt_min > c.integration.dt_max)
    throw InputError(fmt::format("{}: key 'time_integration.dt_min' = {} exceeds time_integration.dt_max = {}",
                                 p.origin(), c.integration.dt_min, c.integration.dt_max));
  c.space.periodic = p.flag("initial_conditions.periodic");
  c.space.split_size = static_cast<int>(p.integer("space.cell_split_size"));
  c.space.top_cells = static_cast<int>(p.integer("space.top_cells"));
  c.space.top_cells_origin = p.where("space.top_cells");
  c.space.skin = p.real("space.rebuild_skin");
  c.repartition_imbalance = p.real("domain.repartition_imbalance");
  c.repartition_min_steps = p.integer("domain.repartition_min_steps");
  c.units.length_cgs = p.real("units.length_cgs");
  c.units.mass_cgs = p.real("units.mass_cgs");
  c.units.velocity_cgs = p.real("units.velocity_cgs");
  c.gravity = GravityParams::from(p, c.units);
  c.cooling = CoolingParams::from(p);
  c.feedback = FeedbackParams::from(p);
  c.star_formation = StarFormationParams::from(p);
  c.output.directory = p.text("output.directory");
  c.output.basename = p.text("output.basename");
  c.output.delta_time = p.real("output.delta_time");
  c.output.dump_task_graph = p.flag("output.dump_task_graph");
  c.output.dump_timeline_every = p.integer("output.dump_timeline_every");
  c.output.statistics_every = p.integer("output.statistics_every");
  c.restart.every_steps = p.integer("restart.every_steps");
  c.restart.every_minutes = p.real("restart.every_minutes");
  c.parameters_yaml = p.used_as_yaml();
  c.check_times(p, "run.t_begin");
  return c;
}

void RunConfig::check_times(const ParameterFile& p, const std::string& start_origin) const {
  if (!(t_end > t_begin))
    throw InputError(fmt::format("{} = {} must be later than the start time {} ({})", p.where("run.t_end"), t_end,
                                 t_begin, start_origin));
  // Every step and every output time is a whole number of ticks of the integer timeline.
  const TimeLine timeline{t_begin, t_end};
  if (timeline.bin_for(integration.dt_max) < 0)
    throw InputError(fmt::format("{} = {} is shorter than one tick ({}); shorten the run or raise dt_max",
                                 p.where("time_integration.dt_max"), integration.dt_max,
                                 integration::tick_text(timeline)));
  if (output.delta_time > 0.0 && !(output.delta_time >= timeline.time_base()))
    throw InputError(fmt::format("{} = {} is shorter than one tick ({}), so snapshots could not be told apart in "
                                 "time; raise it (0 writes only the first and the last snapshot)",
                                 p.where("output.delta_time"), output.delta_time, integration::tick_text(timeline)));
}

}  // namespace fountain
