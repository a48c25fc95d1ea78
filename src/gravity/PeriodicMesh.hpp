// The long-range half of periodic TreePM gravity: mass onto a mesh, Poisson's equation by FFT, forces back to the particles.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "core/ForEach.hpp"
#include "core/Vec3.hpp"
#include "gravity/GravityKernel.hpp"
#include "gravity/MeshSlabs.hpp"

namespace fountain::gravity {

// GADGET-2's particle-mesh part (docs/gravity.md, "Periodic TreePM"), in the comoving box
// [0, L)^3 with a uniform background removed (the k = 0 mode):
//  1. cloud-in-cell assignment of the masses to N^3 nodes, summed in 64-bit fixed point, so
//     the mesh density is the same bits whatever the order of the particles or the threads;
//  2. Phi_k = -4 pi G rho_k exp(-k^2 r_s^2) / (k^2 W(k)^2), W the CIC window per axis
//     sinc^2(k_d Delta / 2) (its square undoes the assignment's and the interpolation's
//     smoothing), the Nyquist planes zeroed;
//  3. the gradient by fourth-order finite differences on the mesh, and cloud-in-cell
//     interpolation back to each particle with its own weights.
// What it leaves out is exactly the short-range force GravitySplit{r_s} gives the tree.
//
// The 3D transform is taken as FFTW's MPI transforms take it, but with plans of our own: a 2D
// transform of each x-plane, a transpose to y-planes, 1D transforms along x, and back. Each
// plane's transform is the same plan on the same numbers wherever it runs, so the result has
// the same bits on any number of threads (which share the planes) and of ranks (which hold
// slabs of them, `MeshSlabs`): no rank holds a copy of the whole mesh.
class PeriodicMesh {
 public:
  // cells: N, even and at least 8; box: L; r_s: the split scale (GADGET's 1.25 mesh cells is
  // `default_split_scale`); G: Newton's constant in the run's units; slabs: the ranks that
  // share the mesh (null: this process holds all of it).
  PeriodicMesh(int cells, double box, double r_s, double G, std::unique_ptr<MeshSlabs> slabs = nullptr);
  ~PeriodicMesh();
  PeriodicMesh(const PeriodicMesh&) = delete;
  PeriodicMesh& operator=(const PeriodicMesh&) = delete;

  static double default_split_scale(int cells, double box) { return 1.25 * box / cells; }

  // The long-range acceleration and potential at every particle. Positions outside [0, L)
  // are wrapped. Across ranks every rank passes every particle (the same arrays) and gets
  // every particle's force: each rank assigns and interpolates only at its own planes. The
  // potential includes the constants that make mesh + short range the periodic potential of
  // docs/gravity.md: 4 pi G r_s^2 M / L^3 (the background's short-range part, which no pair
  // sum subtracts) and G m / (sqrt(pi) r_s) (the particle's own smoothed self-potential on
  // the mesh).
  void compute(std::span<const Vec3> positions, std::span<const double> masses, std::span<Vec3> acceleration,
               std::span<double> potential, const ForEach& for_each = {});
  // Receives a particle's index, long-range acceleration and potential; it may be called from
  // any thread, once per index.
  using ForceSink = std::function<void(std::size_t, const Vec3&, double)>;
  // The same where each rank passes only its own particles and gets their forces: each goes
  // to the ranks whose planes its cloud reaches, and comes back from the one that interpolates
  // it. The mesh and every force have compute()'s bits over all ranks' particles together.
  // The particles travel in rounds, each a run of planes that receives at most
  // round_particles() particles (more only where one plane holds more), so the exchange's
  // memory follows a round, not the particle count. Collective.
  // The particles are read where they lie, by index in [0, count).
  struct Sources {
    std::size_t count = 0;
    std::function<Vec3(std::size_t)> position;
    std::function<double(std::size_t)> mass;
  };
  void compute_owned(const Sources& sources, const ForceSink& store, const ForEach& for_each = {});
  void set_round_bytes(std::size_t bytes);
  std::size_t round_particles() const { return round_particles_; }

  // The assigned mass per node of this rank's planes in the last compute, in the fixed-point
  // units (node index ((i - first_plane()) N + j) N + k for node position (i, j, k) Delta):
  // what must not depend on threads or ranks.
  const std::vector<std::int64_t>& assigned_mass() const { return fixed_; }
  // This rank's x-planes: [first_plane(), first_plane() + planes()).
  int first_plane() const { return x0_; }
  int planes() const { return nx_; }
  // Bytes of mesh this rank holds (its planes of density and transform and its Green's
  // function; the gradient is made two planes at a time per task): about 1 / ranks of one
  // process's.
  std::size_t bytes() const;
  GravitySplit split() const { return GravitySplit{r_s_}; }
  int cells() const { return n_; }
  double box() const { return box_; }

 private:
  // The masses' smallest positive and largest value and their count: the fixed-point unit.
  struct MassRange {
    double min = 0.0, max = 0.0;
    std::int64_t count = 0;
  };
  static MassRange mass_range(std::size_t count, const std::function<double(std::size_t)>& mass);
  void assign(std::span<const Vec3> positions, std::span<const double> masses, const ForEach& for_each);
  // The assignment in parts: the fixed-point unit set and the mesh cleared, then masses added (in
  // any order and any parts: the sums are integers).
  void begin_deposit(const MassRange& range);
  void add_masses(std::span<const Vec3> positions, std::span<const double> masses, const ForEach& for_each);
  // The potential's constant part, 4 pi G r_s^2 M / L^3 (M from the mesh). Collective.
  double background_potential() const;
  // The force and potential at each of `positions` whose lower plane is this rank's, given to
  // store(index, acceleration, potential) (from any thread, each index once); the others are
  // skipped.
  template <class Store>
  void interpolate(std::span<const Vec3> positions, std::span<const double> masses, const Store& store,
                   double background, const ForEach& for_each);
  void solve(const ForEach& for_each);
  void transpose(bool to_columns, const ForEach& for_each);
  std::vector<double> green_function() const;
  double* plane(int local);  // this rank's local plane (-2 ... planes() + 2 with the ghosts)
  std::size_t plane_doubles() const;

  int n_;
  double box_, r_s_, G_;
  std::unique_ptr<MeshSlabs> slabs_;
  int x0_ = 0, nx_ = 0;  // this rank's planes
  double fixed_unit_ = 1.0;  // mass of one fixed-point unit
  std::size_t round_particles_ = 26214;  // compute_owned's rounds: 1 MiB of 40-byte records
  std::vector<std::int64_t> fixed_;
  std::vector<double> green_;     // per mode of this rank's y-planes (green_function)
  struct Fft;
  std::unique_ptr<Fft> fft_;
};

}  // namespace fountain::gravity
