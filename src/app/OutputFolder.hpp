// A run's output folder: one run at a time holds it, and no run writes over what it must keep.
#pragma once
#include <string>
#include <vector>

namespace fountain {

// An exclusive lock on an output folder, held until destruction: `<dir>/.fountain.lock`,
// locked with flock() and naming its holder (host and PID). The kernel drops the lock when
// its holder dies, so the file a killed run left behind is recognised as stale and taken over.
class OutputFolderLock {
 public:
  static constexpr const char* kFileName = ".fountain.lock";
  // Throws InputError naming the folder and the holder when another run holds it.
  explicit OutputFolderLock(const std::string& directory);
  ~OutputFolderLock();
  OutputFolderLock(const OutputFolderLock&) = delete;
  OutputFolderLock& operator=(const OutputFolderLock&) = delete;
  // The holder named by a stale lock this one replaced ("" when there was none).
  const std::string& stale_holder() const { return stale_holder_; }
  // Why the folder could not be locked, on a file system without flock ("" when locked).
  const std::string& unsupported() const { return unsupported_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::string stale_holder_;
  std::string unsupported_;
};

// Whether `file` is one a run with this folder and snapshot basename writes (a snapshot, a
// restart file or piece, the statistics, a task-graph or timeline dump).
bool is_run_output(const std::string& directory, const std::string& basename, const std::string& file);

// The files of an earlier run in the folder that a fresh run would replace: snapshots of
// this basename, restart files and pieces, statistics.
std::vector<std::string> earlier_run_outputs(const std::string& directory, const std::string& basename);

// Before a run writes anything: throws InputError if one of `inputs` (the initial conditions,
// the parameter file) is among the files the run writes; for a fresh run (not `restart`), if
// the folder holds an earlier run's outputs, throws InputError naming them unless `overwrite`,
// which removes them (so no stale snapshot of the earlier run is left among the new ones).
void guard_output_folder(const std::string& directory, const std::string& basename,
                         const std::vector<std::string>& inputs, bool restart, bool overwrite);

}  // namespace fountain
