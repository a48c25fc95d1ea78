// The periodic mesh shared among MPI ranks as FFTW's slabs: which planes each rank holds, the transposes between them, and the mesh's other messages.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace fountain::gravity {

// FFTW's planner is not thread-safe (its executors are): every plan is made and destroyed
// under this lock.
std::mutex& fftw_planner_mutex();

// FFTW's MPI slab decomposition of an N^3 mesh: rank r holds the x-planes
// [first_plane(r), first_plane(r) + planes(r)) of the real mesh and, after the transpose, the
// same block of y-planes of the transformed one (FFTW's default blocks, ceil(N / ranks)
// planes each, so late ranks may hold fewer or none). Every rank knows every rank's block,
// so the ghost planes' messages need no negotiation.
class MeshSlabs {
 public:
  // The ranks of MPI_COMM_WORLD, or null when the process runs alone (MPI not started by a
  // launcher, one rank, or a build without MPI). Collective.
  static std::unique_ptr<MeshSlabs> world(int cells);
  ~MeshSlabs();
  MeshSlabs(const MeshSlabs&) = delete;
  MeshSlabs& operator=(const MeshSlabs&) = delete;

  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  int first_plane(int r) const;
  int planes(int r) const;
  int owner_of(int plane) const { return plane / block_; }
  // How many doubles each of the two transposed buffers must hold (FFTW's figure: at least
  // the rank's planes, more where its transpose wants room).
  std::size_t buffer_doubles() const { return buffer_doubles_; }

  // Plans the transposes between `planes` (this rank's x-planes, each N rows of 2 (N/2 + 1)
  // doubles) and `columns` (its y-planes, rows alike). Collective; the buffers must stay in
  // place for the slabs' life.
  void plan_transposes(double* planes, double* columns);
  void transpose_to_columns();
  void transpose_to_planes();

  // Fills the ghost planes around this rank's block in `buffer`: `before` planes, then its
  // own, then `after` planes, each `plane_doubles` long, with the periodic neighbours' planes
  // from whichever rank holds them (itself included). Collective.
  void fill_ghost_planes(double* buffer, std::size_t plane_doubles, int before, int after) const;
  // Every rank's values combined by their bits: each value must be set by one rank only and
  // left +0.0 (all bits clear) by the others, so the result is that rank's value exactly.
  void combine_bits(std::span<double> values) const;
  std::int64_t sum(std::int64_t local) const;
  // Each element summed over the ranks, in place (every rank passes as many). Collective.
  void sum(std::span<std::int64_t> values) const;
  double min(double local) const;
  double max(double local) const;
  // Sends `bytes` (to each rank q in turn, itself included, counts[q] bytes) and returns what
  // every rank sent this one, laid end to end in rank order, with their byte counts in
  // `counts`. The send buffer is freed once sent: an exchange holds at most both. Collective.
  std::vector<char> exchange(std::vector<char>&& bytes, std::vector<std::size_t>& counts) const;

 private:
  MeshSlabs() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int n_ = 0, rank_ = 0, ranks_ = 1, block_ = 1;
  std::size_t buffer_doubles_ = 0;
};

}  // namespace fountain::gravity
