#include "gravity/MeshSlabs.hpp"

#include <fftw3.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "tasks/MpiSession.hpp"

#ifdef FOUNTAIN_HAVE_MPI
#include <fftw3-mpi.h>
#include <mpi.h>
#endif

namespace fountain::gravity {

std::mutex& fftw_planner_mutex() {
  static std::mutex m;
  return m;
}

int MeshSlabs::first_plane(int r) const { return std::min(n_, r * block_); }
int MeshSlabs::planes(int r) const { return std::min(n_, (r + 1) * block_) - first_plane(r); }

#ifdef FOUNTAIN_HAVE_MPI

struct MeshSlabs::Impl {
  MPI_Comm comm = MPI_COMM_NULL;
  fftw_plan to_columns = nullptr, to_planes = nullptr;
};

namespace {
void check(int err, const char* what) {
  if (err != MPI_SUCCESS) throw std::runtime_error(std::string("MPI call failed in the periodic mesh: ") + what);
}
}  // namespace

std::unique_ptr<MeshSlabs> MeshSlabs::world(int cells) {
  const int size = tasks::MpiSession::world_size();
  if (size < 2) return nullptr;
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    static bool started = false;  // fftw_mpi_init is called once, after MPI_Init
    if (!started) fftw_mpi_init();
    started = true;
  }
  std::unique_ptr<MeshSlabs> s(new MeshSlabs());
  s->impl_ = std::make_unique<Impl>();
  check(MPI_Comm_dup(MPI_COMM_WORLD, &s->impl_->comm), "MPI_Comm_dup");
  MPI_Comm_rank(s->impl_->comm, &s->rank_);
  s->ranks_ = size;
  s->n_ = cells;
  const std::ptrdiff_t n[2] = {cells, cells};
  const std::ptrdiff_t row = 2 * (cells / 2 + 1);
  std::ptrdiff_t n0 = 0, start0 = 0, n1 = 0, start1 = 0;
  const std::ptrdiff_t alloc = fftw_mpi_local_size_many_transposed(
      2, n, row, FFTW_MPI_DEFAULT_BLOCK, FFTW_MPI_DEFAULT_BLOCK, s->impl_->comm, &n0, &start0, &n1, &start1);
  // FFTW's default block, which the ranks' blocks are computed from without asking it again.
  s->block_ = (cells + size - 1) / size;
  // (A rank past the last block holds nothing, wherever FFTW says its nothing starts.)
  if (n0 != s->planes(s->rank_) || n1 != n0 || (n0 > 0 && (start0 != s->first_plane(s->rank_) || start1 != start0)))
    throw std::logic_error("MeshSlabs: FFTW's slabs are not the blocks of ceil(N / ranks) planes assumed");
  s->buffer_doubles_ = static_cast<std::size_t>(std::max<std::ptrdiff_t>({alloc, n0 * cells * row, std::ptrdiff_t{1}}));
  return s;
}

MeshSlabs::~MeshSlabs() {
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    if (impl_->to_columns) fftw_destroy_plan(impl_->to_columns);
    if (impl_->to_planes) fftw_destroy_plan(impl_->to_planes);
  }
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && impl_->comm != MPI_COMM_NULL) MPI_Comm_free(&impl_->comm);
}

void MeshSlabs::plan_transposes(double* planes, double* columns) {
  std::lock_guard<std::mutex> lock(fftw_planner_mutex());
  const std::ptrdiff_t r = 2 * (n_ / 2 + 1);
  impl_->to_columns = fftw_mpi_plan_many_transpose(n_, n_, r, FFTW_MPI_DEFAULT_BLOCK, FFTW_MPI_DEFAULT_BLOCK, planes,
                                                   columns, impl_->comm, FFTW_ESTIMATE);
  impl_->to_planes = fftw_mpi_plan_many_transpose(n_, n_, r, FFTW_MPI_DEFAULT_BLOCK, FFTW_MPI_DEFAULT_BLOCK, columns,
                                                  planes, impl_->comm, FFTW_ESTIMATE);
  if (!impl_->to_columns || !impl_->to_planes)
    throw std::runtime_error("MeshSlabs: FFTW could not plan the transposes between the ranks' slabs");
}

void MeshSlabs::transpose_to_columns() { fftw_execute(impl_->to_columns); }
void MeshSlabs::transpose_to_planes() { fftw_execute(impl_->to_planes); }

void MeshSlabs::fill_ghost_planes(double* buffer, std::size_t plane_doubles, int before, int after) const {
  if (plane_doubles > static_cast<std::size_t>(INT_MAX)) throw std::runtime_error("MeshSlabs: a mesh plane over 2^31 values");
  const int count = static_cast<int>(plane_doubles);
  const int slots = before + after;
  // Slot s of rank r: the plane it needs there, and the position of that plane in its buffer.
  auto wanted = [&](int r, int s) {
    const int p = s < before ? first_plane(r) - before + s : first_plane(r) + planes(r) + (s - before);
    return ((p % n_) + n_) % n_;
  };
  auto position = [&](int r, int s) { return s < before ? s : before + planes(r) + (s - before); };
  std::vector<MPI_Request> requests;
  for (int r = 0; r < ranks_; ++r) {
    if (r == rank_ || planes(r) == 0) continue;
    for (int s = 0; s < slots; ++s) {
      const int p = wanted(r, s);
      if (owner_of(p) != rank_) continue;
      const double* from = buffer + static_cast<std::size_t>(before + p - first_plane(rank_)) * plane_doubles;
      requests.emplace_back();
      check(MPI_Isend(from, count, MPI_DOUBLE, r, s, impl_->comm, &requests.back()), "MPI_Isend (ghost plane)");
    }
  }
  if (planes(rank_) > 0) {
    for (int s = 0; s < slots; ++s) {
      const int p = wanted(rank_, s);
      double* to = buffer + static_cast<std::size_t>(position(rank_, s)) * plane_doubles;
      if (owner_of(p) == rank_) {
        std::memcpy(to, buffer + static_cast<std::size_t>(before + p - first_plane(rank_)) * plane_doubles,
                    plane_doubles * sizeof(double));
      } else {
        requests.emplace_back();
        check(MPI_Irecv(to, count, MPI_DOUBLE, owner_of(p), s, impl_->comm, &requests.back()), "MPI_Irecv (ghost plane)");
      }
    }
  }
  check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall (ghost planes)");
}

void MeshSlabs::combine_bits(std::span<double> values) const {
  static_assert(sizeof(double) == sizeof(std::uint64_t));
  constexpr std::size_t kChunk = std::size_t{1} << 26;
  for (std::size_t at = 0; at < values.size(); at += kChunk) {
    const int count = static_cast<int>(std::min(kChunk, values.size() - at));
    check(MPI_Allreduce(MPI_IN_PLACE, values.data() + at, count, MPI_UINT64_T, MPI_BOR, impl_->comm),
          "MPI_Allreduce (mesh forces)");
  }
}

std::int64_t MeshSlabs::sum(std::int64_t local) const {
  std::int64_t total = 0;
  check(MPI_Allreduce(&local, &total, 1, MPI_INT64_T, MPI_SUM, impl_->comm), "MPI_Allreduce (mesh mass)");
  return total;
}

void MeshSlabs::sum(std::span<std::int64_t> values) const {
  constexpr std::size_t kChunk = 1 << 20;
  for (std::size_t at = 0; at < values.size(); at += kChunk) {
    const int count = static_cast<int>(std::min(kChunk, values.size() - at));
    check(MPI_Allreduce(MPI_IN_PLACE, values.data() + at, count, MPI_INT64_T, MPI_SUM, impl_->comm),
          "MPI_Allreduce (mesh counts)");
  }
}

double MeshSlabs::min(double local) const {
  double out = 0.0;
  check(MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_MIN, impl_->comm), "MPI_Allreduce (mesh minimum)");
  return out;
}

double MeshSlabs::max(double local) const {
  double out = 0.0;
  check(MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_MAX, impl_->comm), "MPI_Allreduce (mesh maximum)");
  return out;
}

std::vector<char> MeshSlabs::exchange(std::vector<char>&& bytes, std::vector<std::size_t>& counts) const {
  const auto n = static_cast<std::size_t>(ranks_);
  if (counts.size() != n) throw std::invalid_argument("MeshSlabs::exchange: one count per rank");
  // Byte counts go as MPI's int: an exchange stays below 2 GiB a rank (a particle's record is
  // a few tens of bytes).
  std::vector<int> send_counts(n), recv_counts(n), send_at(n), recv_at(n);
  std::size_t total = 0;
  for (std::size_t q = 0; q < n; ++q) {
    send_at[q] = static_cast<int>(total);
    total += counts[q];
    if (total > static_cast<std::size_t>(INT_MAX)) throw std::runtime_error("MeshSlabs::exchange: more than 2 GiB to send");
    send_counts[q] = static_cast<int>(counts[q]);
  }
  if (total != bytes.size()) throw std::invalid_argument("MeshSlabs::exchange: counts and bytes disagree");
  check(MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, impl_->comm),
        "MPI_Alltoall (mesh message sizes)");
  std::size_t in_total = 0;
  for (std::size_t q = 0; q < n; ++q) {
    recv_at[q] = static_cast<int>(in_total);
    in_total += static_cast<std::size_t>(recv_counts[q]);
    counts[q] = static_cast<std::size_t>(recv_counts[q]);
  }
  if (in_total > static_cast<std::size_t>(INT_MAX)) throw std::runtime_error("MeshSlabs::exchange: more than 2 GiB to receive");
  std::vector<char> in(in_total);
  check(MPI_Alltoallv(bytes.data(), send_counts.data(), send_at.data(), MPI_BYTE, in.data(), recv_counts.data(),
                      recv_at.data(), MPI_BYTE, impl_->comm),
        "MPI_Alltoallv (mesh particles)");
  std::vector<char>().swap(bytes);
  return in;
}

#else  // a build without MPI runs alone

struct MeshSlabs::Impl {};
std::unique_ptr<MeshSlabs> MeshSlabs::world(int) { return nullptr; }
MeshSlabs::~MeshSlabs() = default;
void MeshSlabs::plan_transposes(double*, double*) {}
void MeshSlabs::transpose_to_columns() {}
void MeshSlabs::transpose_to_planes() {}
void MeshSlabs::fill_ghost_planes(double*, std::size_t, int, int) const {}
void MeshSlabs::combine_bits(std::span<double>) const {}
std::int64_t MeshSlabs::sum(std::int64_t local) const { return local; }
void MeshSlabs::sum(std::span<std::int64_t>) const {}
double MeshSlabs::min(double local) const { return local; }
double MeshSlabs::max(double local) const { return local; }
std::vector<char> MeshSlabs::exchange(std::vector<char>&& bytes, std::vector<std::size_t>&) const {
  return std::move(bytes);
}

#endif

}  // namespace fountain::gravity
