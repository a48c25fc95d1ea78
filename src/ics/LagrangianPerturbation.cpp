#include "ics/LagrangianPerturbation.hpp"

#include <fftw3.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <utility>

namespace fountain::ics {

using Complex = std::complex<double>;

// One real-to-complex and one complex-to-real transform of an N^3 grid, planned once
// (FFTW_ESTIMATE: the plan, hence every bit of the result, does not depend on timing), between
// two buffers that every transform of the grid reuses.
class Transforms {
 public:
  explicit Transforms(int n)
      : real_count_(static_cast<std::size_t>(n) * n * n),
        complex_count_(static_cast<std::size_t>(n) * n * (n / 2 + 1)),
        real_(fftw_alloc_real(real_count_)),
        complex_(fftw_alloc_complex(complex_count_)) {
    forward_ = fftw_plan_dft_r2c_3d(n, n, n, real_, complex_, FFTW_ESTIMATE);
    backward_ = fftw_plan_dft_c2r_3d(n, n, n, complex_, real_, FFTW_ESTIMATE);
  }
  ~Transforms() {
    fftw_destroy_plan(forward_);
    fftw_destroy_plan(backward_);
    fftw_free(real_);
    fftw_free(complex_);
  }
  Transforms(const Transforms&) = delete;
  Transforms& operator=(const Transforms&) = delete;

  // The buffers: forward() reads grid() into coefficients(), backward() the other way.
  std::span<double> grid() { return {real_, real_count_}; }
  std::span<Complex> coefficients() { return {reinterpret_cast<Complex*>(complex_), complex_count_}; }

  std::vector<Complex> forward(const std::vector<double>& grid) {
    std::memcpy(real_, grid.data(), real_count_ * sizeof(double));
    fftw_execute(forward_);
    const std::span<Complex> c = coefficients();
    return {c.begin(), c.end()};
  }
  // The real field of coefficients() (the inverse, with its 1/N^3), in grid(); destroys
  // coefficients().
  std::span<const double> backward() {
    fftw_execute(backward_);
    const double norm = 1.0 / static_cast<double>(real_count_);
    for (double& v : grid()) v *= norm;
    return grid();
  }

 private:
  std::size_t real_count_, complex_count_;
  double* real_;
  fftw_complex* complex_;
  fftw_plan forward_, backward_;
};

namespace {

// Writes into `out` the coefficients of a derived field: each mode of `source` times
// f(k, mode), Nyquist modes and k = 0 zero, times the phase that evaluates the field `shift`
// cells on.
template <class F>
void derive(std::span<Complex> out, const SpectralField& source, double shift, F&& f) {
  const int n = source.n;
  const double cell = source.box / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k) {
        const std::size_t at = source.index(i, j, k);
        if (source.nyquist(i, j, k) || (i == 0 && j == 0 && k == 0)) {
          out[at] = 0.0;
          continue;
        }
        const std::array<double, 3> kv{source.wave(i), source.wave(j), source.wave(k)};
        Complex value = f(kv, source.values[at]);
        if (shift != 0.0) value *= std::polar(1.0, (kv[0] + kv[1] + kv[2]) * shift * cell);
        out[at] = value;
      }
}

double k2(const std::array<double, 3>& k) { return k[0] * k[0] + k[1] * k[1] + k[2] * k[2]; }

// S = sum_{i<j} phi1,ii phi1,jj - phi1,ij^2 on the cells (phi1,ab = k_a k_b deltahat / k^2 in
// Fourier space): two grids held besides the transforms' own, where all six at once were.
std::vector<double> second_order_source(const SpectralField& delta, Transforms& t) {
  auto second_derivative = [&](int a, int b) {
    derive(t.coefficients(), delta, 0.0, [&](const std::array<double, 3>& k, Complex v) { return k[a] * k[b] * v / k2(k); });
    return t.backward();
  };
  std::span<const double> grid = second_derivative(0, 0);
  std::vector<double> source(grid.begin(), grid.end());  // phi1,xx until the diagonal sum replaces it
  grid = second_derivative(1, 1);
  const std::vector<double> yy(grid.begin(), grid.end());
  const std::span<const double> zz = second_derivative(2, 2);
  for (std::size_t m = 0; m < source.size(); ++m) {
    const double xx = source[m];
    source[m] = xx * yy[m] + xx * zz[m] + yy[m] * zz[m];
  }
  for (auto [a, b] : {std::pair{0, 1}, {0, 2}, {1, 2}}) {
    const std::span<const double> ab = second_derivative(a, b);
    for (std::size_t m = 0; m < source.size(); ++m) source[m] -= ab[m] * ab[m];
  }
  return source;
}

}  // namespace

double SpectralField::wave(int i) const {
  const int m = i <= n / 2 ? i : i - n;
  return 2.0 * std::numbers::pi * m / box;
}

SpectralField forward_transform(const std::vector<double>& grid, int n, double box) {
  Transforms t(n);
  SpectralField f{n, box, t.forward(grid)};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k)
        if (f.nyquist(i, j, k)) f.values[f.index(i, j, k)] = 0.0;
  return f;
}

std::vector<double> real_field(const SpectralField& f, const std::function<double(double)>& filter) {
  Transforms t(f.n);
  derive(t.coefficients(), f, 0.0,
         [&](const std::array<double, 3>& k, Complex v) { return v * filter(std::sqrt(k2(k))); });
  const std::span<const double> grid = t.backward();
  return {grid.begin(), grid.end()};
}

DisplacementFields::DisplacementFields(SpectralField delta, int order)
    : delta_(std::move(delta)), order_(order), transforms_(std::make_unique<Transforms>(delta_.n)) {
  if (order_ < 2) return;
  const std::vector<double> s = second_order_source(delta_, *transforms_);
  source_ = {delta_.n, delta_.box, transforms_->forward(s)};
}

DisplacementFields::~DisplacementFields() = default;

std::span<const double> DisplacementFields::first(int axis, double shift) {
  // psi1 = -grad phi1, phihat1 = -deltahat / k^2: psihat1 = i k deltahat / k^2.
  const Complex i_unit(0.0, 1.0);
  derive(transforms_->coefficients(), delta_, shift,
         [&](const std::array<double, 3>& k, Complex v) { return i_unit * k[axis] * v / k2(k); });
  return transforms_->backward();
}

std::span<const double> DisplacementFields::second(int axis, double shift) {
  // phihat2 = -Shat / k^2; grad phi2 = i k phihat2.
  const Complex i_unit(0.0, 1.0);
  derive(transforms_->coefficients(), source_, shift,
         [&](const std::array<double, 3>& k, Complex v) { return -i_unit * k[axis] * v / k2(k); });
  return transforms_->backward();
}

Displacements lagrangian_displacements(const SpectralField& delta, int order, double shift) {
  DisplacementFields fields(delta, order);
  Displacements d;
  for (int c = 0; c < 3; ++c) {
    const std::span<const double> psi = fields.first(c, shift);
    d.first[c].assign(psi.begin(), psi.end());
  }
  if (order < 2) return d;
  for (int c = 0; c < 3; ++c) {
    const std::span<const double> grad = fields.second(c, shift);
    d.second[c].assign(grad.begin(), grad.end());
  }
  return d;
}

}  // namespace fountain::ics
