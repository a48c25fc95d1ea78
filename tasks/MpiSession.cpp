#include "tasks/MpiSession.hpp"

#include <cstdlib>

#ifdef FOUNTAIN_HAVE_MPI
#include <mpi.h>
#endif

namespace fountain::tasks {

#ifdef FOUNTAIN_HAVE_MPI
namespace {
// Whether a launcher (Open MPI's mpirun, or a PMI/PMIx one such as MPICH's or Slurm's)
// started this process. A plain `fountain ...` then skips MPI_Init: a singleton init costs
// half a second and leaves the library's allocations for leak checkers to report.
bool launched_by_mpirun() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"})
    if (std::getenv(v) != nullptr) return true;
  return false;
}
}  // namespace

MpiSession::MpiSession(int* argc, char*** argv) {
  if (!launched_by_mpirun()) return;
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) {
    // A leaf's ghost results go to each rank that holds it as one message, of 5-30 KB. Open
    // MPI's shared-memory transport sends what is over 4 KB by rendezvous: the receiver copies
    // it out of the sender's memory inside its polls. On 250k Sedov (2 ranks x 1 thread) the
    // polls between tasks took ~0.7 s per rank per run, 0.4-0.5 s with such messages eager.
    // A default only: a value the user set (environment or mpirun --mca) wins.
    setenv("OMPI_MCA_btl_vader_eager_limit", "32768", 0);
    int provided = MPI_THREAD_SINGLE;
    MPI_Init_thread(argc, argv, MPI_THREAD_MULTIPLE, &provided);
    thread_multiple_ = provided >= MPI_THREAD_MULTIPLE;
    initialised_here_ = true;
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() {
  if (!initialised_here_) return;
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (!finalised) MPI_Finalize();
}

bool MpiSession::available() { return true; }

int MpiSession::world_size() {
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) return 1;
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

void MpiSession::abort(int code) const {
  if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}
#else
MpiSession::MpiSession(int*, char***) {}
MpiSession::~MpiSession() = default;
bool MpiSession::available() { return false; }
int MpiSession::world_size() { return 1; }
void MpiSession::abort(int code) const { std::exit(code); }
#endif

}  // namespace fountain::tasks
