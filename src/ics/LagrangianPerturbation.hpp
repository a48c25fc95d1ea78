// First- and second-order Lagrangian perturbation theory on a periodic grid: displacement fields from a linear density field.
#pragma once
#include <array>
#include <complex>
#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace fountain::ics {

// A real field's Fourier coefficients on an N^3 grid in a box of side L, in FFTW's
// real-to-complex layout (N x N x (N/2 + 1), coefficient of cell index m: sum over cells n of
// f_n exp(-2 pi i m.n / N)). Modes with an index N/2 are kept at zero.
struct SpectralField {
  int n = 0;
  double box = 1.0;
  std::vector<std::complex<double>> values;

  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(i) * static_cast<std::size_t>(n) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(n / 2 + 1) + static_cast<std::size_t>(k);
  }
  // The wave number of index i along an axis (2 pi / L times the signed mode).
  double wave(int i) const;
  bool nyquist(int i, int j, int k) const { return i == n / 2 || j == n / 2 || k == n / 2; }
};

// The coefficients of a real N^3 grid (cell (i, j, k) at (i N + j) N + k).
SpectralField forward_transform(const std::vector<double>& grid, int n, double box);

// The real field of `f` on its N^3 cells, each mode times filter(|k|) (k = 0 and the Nyquist
// modes dropped): a smoothed density, say.
std::vector<double> real_field(const SpectralField& f, const std::function<double(double)>& filter);

class Transforms;  // FFTW's plans and buffers for one grid size (LagrangianPerturbation.cpp)

// The displacement fields of a linear density `delta` (at D = 1), one component at a time:
// positions are q + D psi1 + D2 grad phi2, with psi1 = -grad phi1, lap phi1 = delta, and
// lap phi2 = sum_{i<j} phi1,ii phi1,jj - phi1,ij^2. A component is an N^3 grid in a buffer the
// fields share and reuse, so that a box's particles take its values as they come rather than
// six grids being held at once; the transforms are planned once, and phi2's source (of delta
// alone) is worked out once for every species and shift.
class DisplacementFields {
 public:
  // order 1: Zel'dovich; 2: 2LPT (its source is worked out here).
  DisplacementFields(SpectralField delta, int order);
  ~DisplacementFields();
  DisplacementFields(const DisplacementFields&) = delete;
  DisplacementFields& operator=(const DisplacementFields&) = delete;

  int order() const { return order_; }
  // Component `axis` of psi1 at the cells moved by `shift` cells along each axis (0: the
  // cells; 0.5: their far corners, where the gas sits), cell (i N + j) N + k at that index.
  // Valid until the next call of first() or second().
  std::span<const double> first(int axis, double shift);
  // The same of grad phi2 (order 2 only).
  std::span<const double> second(int axis, double shift);

 private:
  SpectralField delta_;
  int order_;
  std::unique_ptr<Transforms> transforms_;
  SpectralField source_;  // phi2's source S's coefficients (order 2)
};

// Real displacement fields (one N^3 grid per component) at the cell positions shifted by
// `shift` cells along each axis (0: the cells; 0.5: the cells' far corners, where the gas sits).
struct Displacements {
  std::array<std::vector<double>, 3> first;   // psi1 = -grad phi1, lap phi1 = delta
  std::array<std::vector<double>, 3> second;  // grad phi2, lap phi2 = sum_{i<j} phi1,ii phi1,jj - phi1,ij^2 (empty at order 1)
};

// Zel'dovich (order 1) or 2LPT (order 2) displacements of the linear density `delta` (at
// D = 1), every component at once: positions are q + D psi1 + D2 grad phi2. (Generators take
// them a component at a time from DisplacementFields.)
Displacements lagrangian_displacements(const SpectralField& delta, int order, double shift);

}  // namespace fountain::ics
