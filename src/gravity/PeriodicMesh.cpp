#include "gravity/PeriodicMesh.hpp"

#include <fftw3.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fountain::gravity {

namespace {

// FFTW's planner is not thread-safe; its executors are.
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

int wrap_index(int i, int n) { return ((i % n) + n) % n; }

// A particle's cloud-in-cell cell and weights along one axis: nodes lo and lo + 1 (mod N).
struct AxisWeights {
  int lo;
  double w_lo, w_hi;
};
AxisWeights axis_weights(double x, double cell_inv, int n) {
  const double s = x * cell_inv;
  const double f = std::floor(s);
  AxisWeights a;
  a.w_hi = s - f;
  a.w_lo = 1.0 - a.w_hi;
  a.lo = wrap_index(static_cast<int>(f), n);
  return a;
}

// fn(i, j, k, weight) for the eight nodes of position x's cloud (x folded into [0, box)):
// assignment and interpolation share it, so a particle reads back exactly the weights it gave.
template <class Fn>
void for_each_cloud_node(const Vec3& x, double box, double cell_inv, int n, Fn&& fn) {
  AxisWeights w[3]{};
  for (int d = 0; d < 3; ++d) w[d] = axis_weights(x[d] - box * std::floor(x[d] / box), cell_inv, n);
  for (int corner = 0; corner < 8; ++corner) {
    const int i = (corner & 1) ? (w[0].lo + 1) % n : w[0].lo;
    const int j = (corner & 2) ? (w[1].lo + 1) % n : w[1].lo;
    const int k = (corner & 4) ? (w[2].lo + 1) % n : w[2].lo;
    const double weight = ((corner & 1) ? w[0].w_hi : w[0].w_lo) * ((corner & 2) ? w[1].w_hi : w[1].w_lo) *
                          ((corner & 4) ? w[2].w_hi : w[2].w_lo);
    fn(i, j, k, weight);
  }
}

// fn(p) for every particle p < count, in chunks that for_each may run in parallel.
template <class Fn>
void for_each_particle(const ForEach& for_each, std::size_t count, Fn&& fn) {
  constexpr std::size_t kChunk = 4096;
  for_each_or_serial(for_each, (count + kChunk - 1) / kChunk, [&](std::size_t c) {
    const std::size_t end = std::min(count, (c + 1) * kChunk);
    for (std::size_t p = c * kChunk; p < end; ++p) fn(p);
  });
}

}  // namespace

struct PeriodicMesh::Fft {
  double* data = nullptr;  // N x N x 2 (N/2 + 1) reals, the in-place r2c layout
  fftw_plan forward = nullptr, backward = nullptr;
  ~Fft() {
    std::lock_guard<std::mutex> lock(planner_mutex());
    if (forward) fftw_destroy_plan(forward);
    if (backward) fftw_destroy_plan(backward);
    fftw_free(data);
  }
};

PeriodicMesh::PeriodicMesh(int cells, double box, double r_s, double G)
    : n_(cells), box_(box), r_s_(r_s), G_(G), fft_(std::make_unique<Fft>()) {
  if (cells < 8 || cells % 2 != 0 || cells > 4096)
    throw std::invalid_argument("PeriodicMesh: cells per side must be even and in [8, 4096], got " +
                                std::to_string(cells));
  if (!(box > 0.0) || !std::isfinite(box))
    throw std::invalid_argument("PeriodicMesh: box size must be positive and finite");
  if (!(r_s > 0.0) || !(G > 0.0)) throw std::invalid_argument("PeriodicMesh: r_s and G must be positive");
  if (GravitySplit{r_s}.cutoff_radius() >= 0.5 * box)
    throw std::invalid_argument("PeriodicMesh: the short-range cut-off 4.5 r_s must be below half the box");
  const std::size_t n = static_cast<std::size_t>(n_);
  fixed_.assign(n * n * n, 0);
  const std::size_t reals = n * n * 2 * (n / 2 + 1);
  fft_->data = static_cast<double*>(fftw_malloc(sizeof(double) * reals));
  if (!fft_->data) throw std::bad_alloc();
  green_ = green_function();
  std::lock_guard<std::mutex> lock(planner_mutex());
  auto* complex = reinterpret_cast<fftw_complex*>(fft_->data);
  fft_->forward = fftw_plan_dft_r2c_3d(n_, n_, n_, fft_->data, complex, FFTW_ESTIMATE);
  fft_->backward = fftw_plan_dft_c2r_3d(n_, n_, n_, complex, fft_->data, FFTW_ESTIMATE);
  if (!fft_->forward || !fft_->backward) throw std::runtime_error("PeriodicMesh: FFTW could not plan the transforms");
}

PeriodicMesh::~PeriodicMesh() = default;

std::size_t PeriodicMesh::real_index(int i, int j, int k) const {
  const auto n = static_cast<std::size_t>(n_);
  return (static_cast<std::size_t>(i) * n + static_cast<std::size_t>(j)) * 2 * (n / 2 + 1) + static_cast<std::size_t>(k);
}

// Masses are counted in units of m_min 2^-b: 2^-40 of the smallest mass where the sum
// cannot overflow (N m_max / m_min < 2^22), coarser otherwise. The unit depends only on the
// set, and integer sums do not depend on their order.
void PeriodicMesh::assign(std::span<const Vec3> positions, std::span<const double> masses, const ForEach& for_each) {
  double m_min = 0.0, m_max = 0.0;
  for (std::size_t p = 0; p < masses.size(); ++p) {
    const double m = masses[p];
    if (!(m >= 0.0) || !std::isfinite(m))
      throw std::invalid_argument("PeriodicMesh: particle " + std::to_string(p) + " has a negative or non-finite mass");
    if (m > 0.0) m_min = m_min == 0.0 ? m : std::min(m_min, m);
    m_max = std::max(m_max, m);
  }
  std::fill(fixed_.begin(), fixed_.end(), 0);
  if (m_max == 0.0) return;
  const double bound = static_cast<double>(masses.size()) * (m_max / m_min);
  const int bits = std::min(40, 61 - static_cast<int>(std::ceil(std::log2(bound))));
  if (bits < 0) throw std::invalid_argument("PeriodicMesh: the masses span too wide a range for the fixed-point sum");
  fixed_unit_ = std::ldexp(m_min, -bits);
  const double unit_inv = 1.0 / fixed_unit_;
  const double cell_inv = n_ / box_;
  for_each_particle(for_each, positions.size(), [&](std::size_t p) {
    const Vec3& x = positions[p];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
      throw std::invalid_argument("PeriodicMesh: particle " + std::to_string(p) + " has a non-finite position");
    const double m = masses[p] * unit_inv;
    for_each_cloud_node(x, box_, cell_inv, n_, [&](int i, int j, int k, double weight) {
      const auto add = static_cast<std::int64_t>(std::llround(m * weight));
      const std::size_t node = (static_cast<std::size_t>(i) * n_ + j) * n_ + k;
      std::atomic_ref<std::int64_t>(fixed_[node]).fetch_add(add, std::memory_order_relaxed);
    });
  });
}

// The Green's function per mode of the r2c layout, with the FFT's normalisation: it depends
// only on the mesh, so the constructor computes it once rather than every solve (an exp per
// mode).
std::vector<double> PeriodicMesh::green_function() const {
  const int n = n_;
  const double cell = box_ / n;
  const int nk = n / 2 + 1;
  const double k_unit = 2.0 * std::numbers::pi / box_;
  const double norm = 1.0 / (static_cast<double>(n) * n * n);
  // sinc^2 of k_d Delta / 2 per axis index, and k_d itself.
  std::vector<double> kd(static_cast<std::size_t>(n)), window(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int m = i <= n / 2 ? i : i - n;
    kd[static_cast<std::size_t>(i)] = k_unit * m;
    const double y = 0.5 * kd[static_cast<std::size_t>(i)] * cell;
    const double sinc = m == 0 ? 1.0 : std::sin(y) / y;
    window[static_cast<std::size_t>(i)] = sinc * sinc;
  }
  std::vector<double> green(static_cast<std::size_t>(n) * n * nk);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < nk; ++k) {
        double& g = green[(static_cast<std::size_t>(i) * n + j) * nk + k];
        // The Nyquist planes and the mean are zeroed.
        if (i == n / 2 || j == n / 2 || k == n / 2 || (i == 0 && j == 0 && k == 0)) {
          g = 0.0;
          continue;
        }
        const double kx = kd[static_cast<std::size_t>(i)], ky = kd[static_cast<std::size_t>(j)],
                     kz = kd[static_cast<std::size_t>(k)];
        const double k2 = kx * kx + ky * ky + kz * kz;
        const double w = window[static_cast<std::size_t>(i)] * window[static_cast<std::size_t>(j)] *
                         window[static_cast<std::size_t>(k)];
        g = -4.0 * std::numbers::pi * G_ * std::exp(-k2 * r_s_ * r_s_) / (k2 * w * w) * norm;
      }
  return green;
}

// Density -> potential, in place in the FFT buffer.
void PeriodicMesh::solve(const ForEach& for_each) {
  const int n = n_;
  const double cell = box_ / n;
  const double density_unit = fixed_unit_ / (cell * cell * cell);
  // The loops over planes go in parallel (each node's arithmetic is its own, so the bits are
  // the same); the transforms stay serial, as FFTW's threaded plans may round differently with
  // the thread count.
  for_each_or_serial(for_each, static_cast<std::size_t>(n), [&](std::size_t plane) {
    const int i = static_cast<int>(plane);
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        fft_->data[real_index(i, j, k)] =
            static_cast<double>(fixed_[(static_cast<std::size_t>(i) * n + j) * n + k]) * density_unit;
  });
  fftw_execute(fft_->forward);

  auto* rho_k = reinterpret_cast<fftw_complex*>(fft_->data);
  const int nk = n / 2 + 1;
  for_each_or_serial(for_each, static_cast<std::size_t>(n), [&](std::size_t plane) {
    const std::size_t row = plane * static_cast<std::size_t>(n) * nk;
    for (std::size_t m = row; m < row + static_cast<std::size_t>(n) * nk; ++m) {
      rho_k[m][0] *= green_[m];
      rho_k[m][1] *= green_[m];
    }
  });
  fftw_execute(fft_->backward);
}

void PeriodicMesh::compute(std::span<const Vec3> positions, std::span<const double> masses,
                           std::span<Vec3> acceleration, std::span<double> potential, const ForEach& for_each) {
  const std::size_t count = positions.size();
  if (masses.size() != count || acceleration.size() != count || potential.size() != count)
    throw std::invalid_argument("PeriodicMesh::compute: positions, masses and outputs differ in length");
  assign(positions, masses, for_each);
  solve(for_each);

  double total_mass = 0.0;
  for (const std::int64_t f : fixed_) total_mass += static_cast<double>(f);
  total_mass *= fixed_unit_;
  const double background = 4.0 * std::numbers::pi * G_ * r_s_ * r_s_ * total_mass / (box_ * box_ * box_);
  const double self = G_ / (std::sqrt(std::numbers::pi) * r_s_);

  const int n = n_;
  const double cell_inv = n / box_;
  const double* phi = fft_->data;
  // The fourth-order difference of the potential along each axis, once per node: each node
  // is read by the clouds of many particles, and each cloud reads eight nodes' three.
  const auto nodes = static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  gradient_.resize(3 * nodes);
  for_each_or_serial(for_each, static_cast<std::size_t>(n), [&](std::size_t plane) {
    const int i = static_cast<int>(plane);
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t node = (static_cast<std::size_t>(i) * n + j) * n + k;
        for (int d = 0; d < 3; ++d) {
          auto at = [&](int shift) {
            int ii = i, jj = j, kk = k;
            (d == 0 ? ii : d == 1 ? jj : kk) += shift;
            return phi[real_index(wrap_index(ii, n), wrap_index(jj, n), wrap_index(kk, n))];
          };
          gradient_[3 * node + static_cast<std::size_t>(d)] = (8.0 * (at(1) - at(-1)) - (at(2) - at(-2))) * (cell_inv / 12.0);
        }
      }
  });
  for_each_particle(for_each, count, [&](std::size_t p) {
    Vec3 acc;
    double pot = 0.0;
    for_each_cloud_node(positions[p], box_, cell_inv, n, [&](int i, int j, int k, double weight) {
      const double* g = &gradient_[3 * ((static_cast<std::size_t>(i) * n + j) * n + k)];
      for (int d = 0; d < 3; ++d) acc[d] -= weight * g[d];
      pot += weight * phi[real_index(i, j, k)];
    });
    acceleration[p] = acc;
    potential[p] = pot + background + self * masses[p];
  });
}

}  // namespace fountain::gravity
