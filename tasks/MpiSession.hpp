// The MPI environment of one process: initialised once in main, finalised on exit; one rank when built without MPI.
#pragma once

namespace fountain::tasks {

// MPI is initialised only when a launcher (mpirun) started the process; a plain run is one
// rank without touching the library. It is initialised with MPI_THREAD_MULTIPLE requested, so that communication tasks can
// post and poll from TBB worker threads; `thread_multiple()` says whether the library gave
// it. Only one session may exist in a process.
class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool thread_multiple() const { return thread_multiple_; }
  // Stops every rank of the run (after a failure on this one) and returns `code` when alone.
  [[noreturn]] void abort(int code) const;
  // Whether this process was built with MPI at all (FOUNTAIN_MPI).
  static bool available();
  // The ranks of MPI_COMM_WORLD once MPI is initialised; 1 before, or without MPI.
  static int world_size();

 private:
  int rank_ = 0;
  int size_ = 1;
  bool thread_multiple_ = true;
  bool initialised_here_ = false;
};

}  // namespace fountain::tasks
