// When a run writes its restart file, and writing it: one file when alone, a set of pieces and a master across ranks.
#pragma once
#include <chrono>
#include <string>

#include "app/OutputSchedule.hpp"
#include "engine/Engine.hpp"

namespace fountain {

class ParameterFile;

// A restart file that is due (by steps or minutes) is written at the next recut the run makes
// anyway: inside a step, before its tasks (Engine::set_after_rebuild), or after a step that
// ended with one, once the step's outputs are written; so when it is written (which depends
// on the wall clock) changes nothing in the run. Only on SIGTERM, or if no recut comes within
// kMostStepsWaiting steps, are the cells recut for it: that recut then starts a path of its
// own (the restarted run follows it, bit for bit).
class RestartPolicy {
 public:
  static constexpr long long kMostStepsWaiting = 1000;

  // serial: of the last set written across ranks (a restart file's; 0 on a fresh run).
  // Registers itself with the engine's recuts until destroyed.
  RestartPolicy(const ParameterFile& params, const RunConfig& config, Engine& engine, const OutputSchedule& outputs,
                const SnapshotSeries& snapshots, long long serial, bool quiet);
  ~RestartPolicy();
  RestartPolicy(const RestartPolicy&) = delete;
  RestartPolicy& operator=(const RestartPolicy&) = delete;

  bool enabled() const { return config_.restart.every_steps > 0 || config_.restart.every_minutes > 0; }
  // Writes the state as it stands: right after a recut of the cells (restore() recuts the
  // same particles into the same cells).
  void save();
  // After a step: notes a restart file that fell due, and writes it when the rules above say.
  // `terminate`: every rank stops now, with a restart file.
  void after_step(const StepInfo& step, bool terminate);
  // No more restart files: the run is ending (its last snapshot comes next).
  void stop() { engine_.set_after_rebuild({}); }

 private:
  const ParameterFile& params_;
  const RunConfig& config_;
  Engine& engine_;
  const OutputSchedule& outputs_;
  const SnapshotSeries& snapshots_;
  long long serial_;
  bool quiet_;
  std::chrono::steady_clock::time_point last_;
  bool wanted_ = false;  // due, waiting for a recut
  long long wanted_since_ = 0;
};

}  // namespace fountain
