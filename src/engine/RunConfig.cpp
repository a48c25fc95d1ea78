#include "engine/RunConfig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string_view>

#include "core/Error.hpp"
#include "params/ParameterFile.hpp"
#include "step/TimeLine.hpp"
#include "timestep/Integration.hpp"

namespace fountain {

namespace {

// The cosmology section and the keys that only comoving runs take, cross-checked.
void read_comoving(const ParameterFile& p, RunConfig& c) {
  ComovingConfig& cc = c.comoving;
  cc.enabled = p.flag("cosmology.enabled");
  constexpr const char* comoving_only[] = {
      "cosmology.omega_m", "cosmology.omega_lambda", "cosmology.omega_b", "cosmology.hubble_param",
      "cosmology.a_begin", "cosmology.a_end", "output.scale_factors", "output.redshifts",
      "time_integration.max_dln_a", "initial_conditions.length_unit_cgs", "initial_conditions.mass_unit_cgs",
      "initial_conditions.velocity_unit_cgs", "initial_conditions.velocity_convention",
      "initial_conditions.h_scaled", "output.fof_groups", "output.hop_groups"};
  if (!cc.enabled) {
    for (const char* key : comoving_only)
      if (p.was_given(key))
        throw InputError(fmt::format("{} is for comoving runs; set cosmology.enabled: true or remove it", p.where(key)));
    return;
  }
  for (const char* key : {"run.t_begin", "run.t_end", "output.delta_time"})
    if (p.was_given(key))
      throw InputError(fmt::format("{} is not used by a comoving run, whose clock is the scale factor: use {}", p.where(key),
                                   std::string_view(key) == "output.delta_time"
                                       ? "output.scale_factors or output.redshifts"
                                       : "cosmology.a_begin and cosmology.a_end"));
  cc.cosmology.omega_m = p.real("cosmology.omega_m");
  cc.cosmology.omega_lambda = p.real("cosmology.omega_lambda");
  cc.cosmology.omega_b = p.real("cosmology.omega_b");
  cc.cosmology.hubble_param = p.real("cosmology.hubble_param");
  if (cc.cosmology.omega_b > cc.cosmology.omega_m)
    throw InputError(fmt::format("{} = {} exceeds cosmology.omega_m = {}", p.where("cosmology.omega_b"),
                                 cc.cosmology.omega_b, cc.cosmology.omega_m));
  cc.a_begin = p.real("cosmology.a_begin");
  cc.a_end = p.real("cosmology.a_end");
  if (!p.flag("initial_conditions.periodic"))
    throw InputError(fmt::format("{}: a comoving run needs a periodic box (initial_conditions.periodic: true)",
                                 p.where("initial_conditions.periodic")));
  ComovingFileConventions& f = cc.files;
  f.length_cgs = p.real("initial_conditions.length_unit_cgs");
  f.mass_cgs = p.real("initial_conditions.mass_unit_cgs");
  f.velocity_cgs = p.real("initial_conditions.velocity_unit_cgs");
  f.gadget_velocities = p.text("initial_conditions.velocity_convention") == "gadget";
  f.h_scaled = p.flag("initial_conditions.h_scaled");
  c.integration.max_dln_a = p.real("time_integration.max_dln_a");
  // The output times: the listed scale factors and redshifts, merged.
  std::vector<double> a = p.reals("output.scale_factors");
  for (std::size_t k = 1; k < a.size(); ++k)
    if (!(a[k] > a[k - 1]))
      throw InputError(fmt::format("{}: the scale factors must increase ({} follows {})", p.where("output.scale_factors"),
                                   a[k], a[k - 1]));
  const std::vector<double> z = p.reals("output.redshifts");
  for (std::size_t k = 0; k < z.size(); ++k) {
    if (k > 0 && !(z[k] < z[k - 1]))
      throw InputError(fmt::format("{}: the redshifts must decrease ({} follows {})", p.where("output.redshifts"), z[k],
                                   z[k - 1]));
    a.push_back(1.0 / (1.0 + z[k]));
  }
  std::sort(a.begin(), a.end());
  a.erase(std::unique(a.begin(), a.end()), a.end());
  c.output.scale_factors = a;
}

}  // namespace

RunConfig RunConfig::from(const ParameterFile& p) {
  RunConfig c;
  read_comoving(p, c);
  c.t_begin = p.real("run.t_begin");
  c.t_end = p.real("run.t_end");
  if (c.comoving.enabled) c.set_comoving_times();
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
  c.space.skin = p.text("space.rebuild_skin") == "auto" ? SpaceConfig::default_skin(c.comoving.enabled)
                                                         : p.real("space.rebuild_skin");
  c.repartition_imbalance = p.real("domain.repartition_imbalance");
  c.repartition_min_steps = p.integer("domain.repartition_min_steps");
  c.message_bytes = static_cast<std::size_t>(p.integer("domain.message_bytes"));
  c.assemble_gravity_tree = p.flag("domain.assemble_gravity_tree");
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
  c.output.gather_particles = static_cast<std::size_t>(p.integer("output.gather_particles"));
  c.output.fof_groups = p.flag("output.fof_groups");
  c.output.hop_groups = p.flag("output.hop_groups");
  c.restart.every_steps = p.integer("restart.every_steps");
  c.restart.every_minutes = p.real("restart.every_minutes");
  c.parameters_yaml = p.used_as_yaml();
  c.check_times(p, "run.t_begin");
  return c;
}

Units RunConfig::physical_units() const {
  if (!comoving.enabled) return units;
  const double h = comoving.cosmology.hubble_param;
  Units u = units;
  u.length_cgs /= h;
  u.mass_cgs /= h;
  return u;
}

void RunConfig::set_comoving_times() {
  // The engine's timeline runs in ln a; before a_begin is known (0: from the file) it is a
  // placeholder that check_times does not judge.
  t_begin = comoving.a_begin > 0.0 ? std::log(comoving.a_begin) : 0.0;
  t_end = std::log(comoving.a_end);
}

void RunConfig::check_times(const ParameterFile& p, const std::string& start_origin) const {
  if (comoving.enabled) {
    if (comoving.a_begin > 0.0 && !(comoving.a_end > comoving.a_begin))
      throw InputError(fmt::format("{} = {} must be later than the starting scale factor {} ({})",
                                   p.where("cosmology.a_end"), comoving.a_end, comoving.a_begin, start_origin));
    return;  // the steps' bounds are checked against the timeline in ln a by the engine
  }
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
