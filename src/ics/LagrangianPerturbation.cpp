#include "ics/LagrangianPerturbation.hpp"

#include <fftw3.h>

#include <cmath>
#include <cstring>
#include <numbers>

namespace fountain::ics {

namespace {

using Complex = std::complex<double>;

// One real-to-complex and one complex-to-real transform of an N^3 grid, planned once
// (FFTW_ESTIMATE: the plan, hence every bit of the result, does not depend on timing).
class Transforms {
 public:
  explicit Transforms(int n)
      : n_(n),
        real_count_(static_cast<std::size_t>(n) * n * n),
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

  std::vector<Complex> forward(const std::vector<double>& grid) {
    std::memcpy(real_, grid.data(), real_count_ * sizeof(double));
    fftw_execute(forward_);
    std::vector<Complex> out(complex_count_);
    std::memcpy(static_cast<void*>(out.data()), complex_, complex_count_ * sizeof(Complex));
    return out;
  }
  // The real field of coefficients c (the inverse, with its 1/N^3).
  std::vector<double> backward(const std::vector<Complex>& c) {
    std::memcpy(static_cast<void*>(complex_), c.data(), complex_count_ * sizeof(Complex));
    fftw_execute(backward_);  // destroys the input copy, not c
    std::vector<double> out(real_, real_ + real_count_);
    const double norm = 1.0 / static_cast<double>(real_count_);
    for (double& v : out) v *= norm;
    return out;
  }

 private:
  int n_;
  std::size_t real_count_, complex_count_;
  double* real_;
  fftw_complex* complex_;
  fftw_plan forward_, backward_;
};

// The coefficients of a derived field: each mode of `source` times f(k, mode), Nyquist modes
// and k = 0 zero, times the phase that evaluates the field `shift` cells on.
template <class F>
std::vector<Complex> derived(const SpectralField& source, double shift, F&& f) {
  const int n = source.n;
  std::vector<Complex> out(source.values.size());
  const double cell = source.box / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k) {
        const std::size_t at = source.index(i, j, k);
        if (source.nyquist(i, j, k) || (i == 0 && j == 0 && k == 0)) continue;
        const std::array<double, 3> kv{source.wave(i), source.wave(j), source.wave(k)};
        Complex value = f(kv, source.values[at]);
        if (shift != 0.0) value *= std::polar(1.0, (kv[0] + kv[1] + kv[2]) * shift * cell);
        out[at] = value;
      }
  return out;
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
  return t.backward(derived(f, 0.0, [&](const std::array<double, 3>& k, Complex v) {
    return v * filter(std::sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]));
  }));
}

Displacements lagrangian_displacements(const SpectralField& delta, int order, double shift) {
  Transforms t(delta.n);
  Displacements d;
  const Complex i_unit(0.0, 1.0);
  auto k2 = [](const std::array<double, 3>& k) { return k[0] * k[0] + k[1] * k[1] + k[2] * k[2]; };
  // psi1 = -grad phi1, phihat1 = -deltahat / k^2: psihat1 = i k deltahat / k^2.
  for (int c = 0; c < 3; ++c)
    d.first[c] = t.backward(
        derived(delta, shift, [&](const std::array<double, 3>& k, Complex v) { return i_unit * k[c] * v / k2(k); }));
  if (order < 2) return d;
  // phi1,ab = k_a k_b deltahat / k^2 in Fourier space, on the cells themselves.
  auto second_derivative = [&](int a, int b) {
    return t.backward(derived(delta, 0.0, [&](const std::array<double, 3>& k, Complex v) { return k[a] * k[b] * v / k2(k); }));
  };
  const std::vector<double> xx = second_derivative(0, 0), yy = second_derivative(1, 1), zz = second_derivative(2, 2);
  std::vector<double> source(xx.size());
  for (std::size_t m = 0; m < source.size(); ++m) source[m] = xx[m] * yy[m] + xx[m] * zz[m] + yy[m] * zz[m];
  for (auto [a, b] : {std::pair{0, 1}, {0, 2}, {1, 2}}) {
    const std::vector<double> ab = second_derivative(a, b);
    for (std::size_t m = 0; m < source.size(); ++m) source[m] -= ab[m] * ab[m];
  }
  const SpectralField s_hat{delta.n, delta.box, t.forward(source)};
  // phihat2 = -Shat / k^2; grad phi2 = i k phihat2.
  for (int c = 0; c < 3; ++c)
    d.second[c] = t.backward(
        derived(s_hat, shift, [&](const std::array<double, 3>& k, Complex v) { return -i_unit * k[c] * v / k2(k); }));
  return d;
}

}  // namespace fountain::ics
