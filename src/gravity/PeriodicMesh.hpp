// The long-range half of periodic TreePM gravity: mass onto a mesh, Poisson's equation by FFT, forces back to the particles.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/ForEach.hpp"
#include "core/Vec3.hpp"
#include "gravity/GravityKernel.hpp"

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
class PeriodicMesh {
 public:
  // cells: N, even and at least 8; box: L; r_s: the split scale (GADGET's 1.25 mesh cells is
  // `default_split_scale`); G: Newton's constant in the run's units.
  PeriodicMesh(int cells, double box, double r_s, double G);
  ~PeriodicMesh();
  PeriodicMesh(const PeriodicMesh&) = delete;
  PeriodicMesh& operator=(const PeriodicMesh&) = delete;

  static double default_split_scale(int cells, double box) { return 1.25 * box / cells; }

  // The long-range acceleration and potential at every particle. Positions outside [0, L)
  // are wrapped. The potential includes the constants that make mesh + short range the
  // periodic potential of docs/gravity.md: 4 pi G r_s^2 M / L^3 (the background's short-range
  // part, which no pair sum subtracts) and G m / (sqrt(pi) r_s) (the particle's own smoothed
  // self-potential on the mesh).
  void compute(std::span<const Vec3> positions, std::span<const double> masses, std::span<Vec3> acceleration,
               std::span<double> potential, const ForEach& for_each = {});

  // The assigned mass per node of the last compute, in the fixed-point units (node index
  // (i N + j) N + k for node position (i, j, k) Delta): what must not depend on threads.
  const std::vector<std::int64_t>& assigned_mass() const { return fixed_; }
  GravitySplit split() const { return GravitySplit{r_s_}; }
  int cells() const { return n_; }
  double box() const { return box_; }

 private:
  void assign(std::span<const Vec3> positions, std::span<const double> masses, const ForEach& for_each);
  void solve(const ForEach& for_each);
  std::vector<double> green_function() const;
  std::size_t real_index(int i, int j, int k) const;

  int n_;
  double box_, r_s_, G_;
  double fixed_unit_ = 1.0;  // mass of one fixed-point unit
  std::vector<std::int64_t> fixed_;
  std::vector<double> green_;     // per mode of the r2c layout (green_function)
  std::vector<double> gradient_;  // the potential's mesh gradient, three per node
  struct Fft;
  std::unique_ptr<Fft> fft_;
};

}  // namespace fountain::gravity
