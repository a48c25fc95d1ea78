#include "app/RestartPolicy.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "app/Simulation.hpp"
#include "io/RestartFile.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

RestartPolicy::RestartPolicy(const ParameterFile& params, const RunConfig& config, Engine& engine,
                             const OutputSchedule& outputs, const SnapshotSeries& snapshots, long long serial,
                             bool quiet)
    : params_(params),
      config_(config),
      engine_(engine),
      outputs_(outputs),
      snapshots_(snapshots),
      serial_(serial),
      quiet_(quiet),
      last_(std::chrono::steady_clock::now()) {
  engine_.set_after_rebuild([this] {
    if (wanted_) save();
  });
}

RestartPolicy::~RestartPolicy() { stop(); }

void RestartPolicy::save() {
  io::RestartState out;
  const std::string path = restart_path(params_);
  out.ti_current = engine_.ti_current();
  out.ti_step_begin = engine_.ti_step_begin();
  out.mesh_step_bin = engine_.mesh_step().bin;
  out.mesh_step_begin = engine_.mesh_step().ti_begin;
  out.steps = engine_.steps();
  out.snapshots_written = snapshots_.written();
  out.next_output = outputs_.next_output();
  out.radiated_energy = engine_.radiated_energy();
  out.next_particle_id = engine_.next_particle_id();
  out.star_formation = engine_.star_formation_total();
  out.parameters_yaml = config_.parameters_yaml;
  if (engine_.ranks() == 1) {
    io::write_restart(path, out, engine_.gas(), engine_.dark_matter());
    io::remove_stale_restart_pieces(path);  // of a set an earlier run on several ranks wrote
  } else {
    // Each rank writes the particles of its own cells (current on it in halo mode too),
    // then rank 0 the master naming the pieces; the previous set stays whole until then.
    ++serial_;
    const auto [gas_owned, dm_owned] = engine_.owned_particles();
    const std::vector<std::size_t> places = engine_.run_places(gas_owned);
    const std::vector<std::uint64_t> gas_index(places.begin(), places.end());
    const std::vector<std::size_t> dm_places = engine_.run_collisionless_places(dm_owned);
    const std::vector<std::uint64_t> dm_index(dm_places.begin(), dm_places.end());
    const std::filesystem::path dir = std::filesystem::path(path).parent_path();
    io::write_restart_piece((dir / io::restart_piece_name(path, serial_, engine_.rank())).string(),
                            io::RestartPieceRows{engine_.gas(), gas_owned, engine_.dark_matter(), dm_owned, gas_index,
                                                 dm_index});
    (void)engine_.any_rank(false);  // every piece is in place before the master names it
    if (engine_.rank() == 0) {
      io::write_restart_master(path, out, serial_, engine_.ranks(), engine_.gas_count(),
                               engine_.collisionless_count());
      io::remove_stale_restart_pieces(path);
    }
  }
  last_ = std::chrono::steady_clock::now();
  wanted_ = false;
  if (!quiet_) fmt::print(stderr, "restart file {} at step {}\n", path, engine_.steps());
}

void RestartPolicy::after_step(const StepInfo& step, bool terminate) {
  const double minutes = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count() / 60.0;
  bool due = (config_.restart.every_steps > 0 && engine_.steps() % config_.restart.every_steps == 0) ||
             (config_.restart.every_minutes > 0 && minutes >= config_.restart.every_minutes);
  // Clocks differ between ranks: they decide together.
  due = engine_.any_rank(due);
  if (due && !wanted_) {
    wanted_ = true;
    wanted_since_ = engine_.steps();
  }
  if (terminate || (wanted_ && engine_.steps() - wanted_since_ >= kMostStepsWaiting)) {
    engine_.rebuild_now();
    save();
  } else if (wanted_ && step.recut_at_end) {
    save();
  }
}

}  // namespace fountain
