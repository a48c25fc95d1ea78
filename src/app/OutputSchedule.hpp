// When a run writes its snapshots (every output.delta_time from its start, never two at one time) and its statistics lines, and writing them.
#pragma once
#include <memory>
#include <string>

#include "analysis/Diagnostics.hpp"
#include "engine/Engine.hpp"
#include "io/GroupFiles.hpp"
#include "io/Snapshot.hpp"
#include "io/StatisticsFile.hpp"

namespace fountain {

// The snapshot times still to come. The engine's steps stop at next_ticks(), so that a
// snapshot is written at its time exactly.
class OutputSchedule {
 public:
  // next_output: the index of the next output time (1 on a fresh run; a restart file's).
  OutputSchedule(const RunConfig& config, const Engine& engine, int next_output);
  IntegerTime next_ticks() const { return ti_out_; }
  int next_output() const { return next_; }
  // Whether the step just done ended at an output time (the run's end has its own snapshot).
  bool due() const { return engine_.ti_current() == ti_out_ && !engine_.finished(); }
  // On to the next output time, once this one is written.
  void advance();

 private:
  IntegerTime ticks_of(int output) const;
  // Never a step of length zero, never two snapshots at one time: an output time at or
  // before the start of the step in progress is passed over. (A restart from inside a step
  // stands at that step's end but redoes it: an output at its end is still to be written.)
  void skip_past();

  const RunConfig& config_;
  const Engine& engine_;
  int next_;
  IntegerTime ti_out_ = 0;
};

// The numbered snapshot files <directory>/<basename>_NNNN.hdf5; rank 0 alone writes them.
class SnapshotSeries {
 public:
  SnapshotSeries(const RunConfig& config, Engine& engine, TemperatureOf temperature, int written, bool quiet);
  // Drifts every particle to now (on every rank) and writes the next snapshot.
  void write();
  int written() const { return written_; }

 private:
  // This rank's own particles as the group finders read them from a snapshot, and the
  // snapshot's header as they read it.
  groups::ParticleSet own_particles() const;
  // Its gas and stars, with the gas's hidden stellar masses as the snapshot stores them.
  void own_baryons(groups::ParticleSet& baryons, std::vector<double>& hidden) const;
  io::GroupInput group_header() const;

  const RunConfig& config_;
  Engine& engine_;
  io::SnapshotInfo info_;
  int written_;
  bool quiet_;
};

// The statistics file's lines (output.statistics_every steps apart): the paper's time series.
class StatisticsSeries {
 public:
  // `append`: a restarted run adds to the file it finds.
  StatisticsSeries(const RunConfig& config, Engine& engine, TemperatureOf temperature, bool append);
  bool enabled() const { return config_.output.statistics_every > 0; }
  // Whether the step just done ends with a line.
  bool due() const {
    return enabled() && (engine_.steps() % config_.output.statistics_every == 0 || engine_.finished());
  }
  // Gathers the state on every rank (a collective), then rank 0 writes the line.
  void write();

 private:
  const RunConfig& config_;
  Engine& engine_;
  TemperatureOf temperature_;
  analysis::FigurePhases phases_;
  std::unique_ptr<io::StatisticsFile> file_;  // rank 0's
  // The star formation rate of a line is the mean since the previous line.
  double sf_mass_before_, sf_time_before_;
};

}  // namespace fountain
