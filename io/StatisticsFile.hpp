// The statistics file: one line of global diagnostics every few steps, for plots and conservation checks.
#pragma once
#include <cstdio>
#include <string>

#include "analysis/Diagnostics.hpp"

namespace fountain::io {

// A whitespace-separated text table with a commented header naming each column and its
// units; numpy.genfromtxt(names=True) reads it. Each line is flushed as written, so a killed
// run keeps what it measured.
class StatisticsFile {
 public:
  // Creates `path` (or, when `append`, continues it after a restart). A comoving run's file
  // says that its time column is the scale factor and its energies peculiar.
  StatisticsFile(const std::string& path, bool append, bool comoving = false);
  ~StatisticsFile();
  StatisticsFile(const StatisticsFile&) = delete;
  StatisticsFile& operator=(const StatisticsFile&) = delete;

  void write(double time, long long step, const analysis::Diagnostics& d);

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

}  // namespace fountain::io
