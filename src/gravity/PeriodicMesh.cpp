#include "gravity/PeriodicMesh.hpp"

#include <fftw3.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fountain::gravity {

namespace {

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

// The cloud of position x (folded into [0, box)): its lowest node and weights per axis.
struct Cloud {
  AxisWeights w[3];
};
Cloud cloud_of(const Vec3& x, double box, double cell_inv, int n) {
  Cloud c{};
  for (int d = 0; d < 3; ++d) c.w[d] = axis_weights(x[d] - box * std::floor(x[d] / box), cell_inv, n);
  return c;
}

// fn(i, j, k, weight) for the eight nodes of a cloud: assignment and interpolation share it,
// so a particle reads back exactly the weights it gave.
template <class Fn>
void for_each_cloud_node(const Cloud& cloud, int n, Fn&& fn) {
  const AxisWeights* w = cloud.w;
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

// The x-planes around a rank's own that the gradient (two each side) and the interpolation
// (one more above) read.
constexpr int kGhostBefore = 2;
constexpr int kGhostAfter = 3;
// Planes interpolated by one task, which makes the gradient of one plane more than it reads.
constexpr int kGradientRun = 8;

}  // namespace

struct PeriodicMesh::Fft {
  double* planes = nullptr;   // x-planes, kGhostBefore + own + kGhostAfter, each N rows of 2 (N/2 + 1) reals
  double* columns = nullptr;  // the transform's y-planes, each N rows (x) of N/2 + 1 complex values (z)
  std::size_t planes_doubles = 0, columns_doubles = 0;
  fftw_plan plane_forward = nullptr, plane_backward = nullptr;  // 2D, real <-> complex, in place
  fftw_plan line_forward = nullptr, line_backward = nullptr;    // 1D along x for a whole y-plane
  ~Fft() {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    for (fftw_plan p : {plane_forward, plane_backward, line_forward, line_backward})
      if (p) fftw_destroy_plan(p);
    fftw_free(planes);
    fftw_free(columns);
  }
};

PeriodicMesh::PeriodicMesh(int cells, double box, double r_s, double G, std::unique_ptr<MeshSlabs> slabs)
    : n_(cells), box_(box), r_s_(r_s), G_(G), slabs_(std::move(slabs)), fft_(std::make_unique<Fft>()) {
  if (cells < 8 || cells % 2 != 0 || cells > 4096)
    throw std::invalid_argument("PeriodicMesh: cells per side must be even and in [8, 4096], got " +
                                std::to_string(cells));
  if (!(box > 0.0) || !std::isfinite(box))
    throw std::invalid_argument("PeriodicMesh: box size must be positive and finite");
  if (!(r_s > 0.0) || !(G > 0.0)) throw std::invalid_argument("PeriodicMesh: r_s and G must be positive");
  if (GravitySplit{r_s}.cutoff_radius() >= 0.5 * box)
    throw std::invalid_argument("PeriodicMesh: the short-range cut-off 4.5 r_s must be below half the box");
  x0_ = slabs_ ? slabs_->first_plane(slabs_->rank()) : 0;
  nx_ = slabs_ ? slabs_->planes(slabs_->rank()) : n_;
  const std::size_t n = static_cast<std::size_t>(n_);
  const std::size_t nx = static_cast<std::size_t>(nx_);
  const std::size_t plane_size = plane_doubles();
  fixed_.assign(nx * n * n, 0);
  // FFTW's transposes may want more room than the planes; the ghosts after them are filled
  // only once the transposes are done.
  const std::size_t transposed = std::max({slabs_ ? slabs_->buffer_doubles() : 0, nx * plane_size, plane_size});
  fft_->planes_doubles = kGhostBefore * plane_size + std::max(transposed, (nx + kGhostAfter) * plane_size);
  fft_->columns_doubles = transposed;
  fft_->planes = static_cast<double*>(fftw_malloc(sizeof(double) * fft_->planes_doubles));
  fft_->columns = static_cast<double*>(fftw_malloc(sizeof(double) * fft_->columns_doubles));
  if (!fft_->planes || !fft_->columns) throw std::bad_alloc();
  green_ = green_function();
  {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    // Unaligned: one plan serves every plane, wherever it starts.
    constexpr unsigned kFlags = FFTW_ESTIMATE | FFTW_UNALIGNED;
    double* p = fft_->planes;
    auto* pc = reinterpret_cast<fftw_complex*>(p);
    auto* c = reinterpret_cast<fftw_complex*>(fft_->columns);
    const int nk = n_ / 2 + 1;
    fft_->plane_forward = fftw_plan_dft_r2c_2d(n_, n_, p, pc, kFlags);
    fft_->plane_backward = fftw_plan_dft_c2r_2d(n_, n_, pc, p, kFlags);
    fft_->line_forward = fftw_plan_many_dft(1, &n_, nk, c, nullptr, nk, 1, c, nullptr, nk, 1, FFTW_FORWARD, kFlags);
    fft_->line_backward = fftw_plan_many_dft(1, &n_, nk, c, nullptr, nk, 1, c, nullptr, nk, 1, FFTW_BACKWARD, kFlags);
    if (!fft_->plane_forward || !fft_->plane_backward || !fft_->line_forward || !fft_->line_backward)
      throw std::runtime_error("PeriodicMesh: FFTW could not plan the transforms");
  }
  if (slabs_) slabs_->plan_transposes(plane(0), fft_->columns);
}

PeriodicMesh::~PeriodicMesh() = default;

std::size_t PeriodicMesh::plane_doubles() const {
  return static_cast<std::size_t>(n_) * 2 * static_cast<std::size_t>(n_ / 2 + 1);
}

double* PeriodicMesh::plane(int local) {
  return fft_->planes + static_cast<std::ptrdiff_t>(local + kGhostBefore) * static_cast<std::ptrdiff_t>(plane_doubles());
}

std::size_t PeriodicMesh::bytes() const {
  return sizeof(std::int64_t) * fixed_.size() + sizeof(double) * green_.size() +
         sizeof(double) * (fft_->planes_doubles + fft_->columns_doubles);
}

// Masses are counted in units of m_min 2^-b: 2^-40 of the smallest mass where the sum
// cannot overflow (N m_max / m_min < 2^22), coarser otherwise. The unit depends only on the
// set, and integer sums do not depend on their order. Each rank adds only the nodes of its
// own planes, from every particle whose cloud reaches them.
PeriodicMesh::MassRange PeriodicMesh::mass_range(std::size_t count, const std::function<double(std::size_t)>& mass) {
  MassRange r;
  r.count = static_cast<std::int64_t>(count);
  for (std::size_t p = 0; p < count; ++p) {
    const double m = mass(p);
    if (!(m >= 0.0) || !std::isfinite(m))
      throw std::invalid_argument("PeriodicMesh: particle " + std::to_string(p) + " has a negative or non-finite mass");
    if (m > 0.0) r.min = r.min == 0.0 ? m : std::min(r.min, m);
    r.max = std::max(r.max, m);
  }
  return r;
}

void PeriodicMesh::assign(std::span<const Vec3> positions, std::span<const double> masses, const ForEach& for_each) {
  begin_deposit(mass_range(masses.size(), [&](std::size_t p) { return masses[p]; }));
  add_masses(positions, masses, for_each);
}

void PeriodicMesh::begin_deposit(const MassRange& range) {
  std::fill(fixed_.begin(), fixed_.end(), 0);
  if (range.max == 0.0) return;
  const double bound = static_cast<double>(range.count) * (range.max / range.min);
  const int bits = std::min(40, 61 - static_cast<int>(std::ceil(std::log2(bound))));
  if (bits < 0) throw std::invalid_argument("PeriodicMesh: the masses span too wide a range for the fixed-point sum");
  fixed_unit_ = std::ldexp(range.min, -bits);
}

void PeriodicMesh::add_masses(std::span<const Vec3> positions, std::span<const double> masses, const ForEach& for_each) {
  const double unit_inv = 1.0 / fixed_unit_;
  const double cell_inv = n_ / box_;
  const int n = n_, x0 = x0_, nx = nx_;
  for_each_particle(for_each, positions.size(), [&](std::size_t p) {
    const Vec3& x = positions[p];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
      throw std::invalid_argument("PeriodicMesh: particle " + std::to_string(p) + " has a non-finite position");
    const Cloud cloud = cloud_of(x, box_, cell_inv, n);
    const int lo = cloud.w[0].lo - x0, hi = (cloud.w[0].lo + 1) % n - x0;
    if ((lo < 0 || lo >= nx) && (hi < 0 || hi >= nx)) return;
    const double m = masses[p] * unit_inv;
    for_each_cloud_node(cloud, n, [&](int i, int j, int k, double weight) {
      const int local = i - x0;
      if (local < 0 || local >= nx) return;
      const auto add = static_cast<std::int64_t>(std::llround(m * weight));
      const std::size_t node = (static_cast<std::size_t>(local) * n + j) * n + k;
      std::atomic_ref<std::int64_t>(fixed_[node]).fetch_add(add, std::memory_order_relaxed);
    });
  });
}

double PeriodicMesh::background_potential() const {
  std::int64_t assigned = 0;
  for (const std::int64_t f : fixed_) assigned += f;
  if (slabs_) assigned = slabs_->sum(assigned);
  const double total_mass = static_cast<double>(assigned) * fixed_unit_;
  return 4.0 * std::numbers::pi * G_ * r_s_ * r_s_ * total_mass / (box_ * box_ * box_);
}

// The Green's function per mode of this rank's y-planes (mode (i, j, k) at ((j - first) N +
// i) (N/2 + 1) + k), with the FFT's normalisation: it depends only on the mesh, so the
// constructor computes it once rather than every solve (an exp per mode).
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
  std::vector<double> green(static_cast<std::size_t>(nx_) * n * nk);
  for (int jl = 0; jl < nx_; ++jl)
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < nk; ++k) {
        const int j = x0_ + jl;
        double& g = green[(static_cast<std::size_t>(jl) * n + i) * nk + k];
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

// Between x-planes ((i N + j) rows of 2 (N/2 + 1) reals) and y-planes ((j N + i) rows): by
// FFTW across ranks, by a copy per plane alone.
void PeriodicMesh::transpose(bool to_columns, const ForEach& for_each) {
  if (slabs_) {
    to_columns ? slabs_->transpose_to_columns() : slabs_->transpose_to_planes();
    return;
  }
  const std::size_t n = static_cast<std::size_t>(n_), row = 2 * (n / 2 + 1);
  double* planes = plane(0);
  double* columns = fft_->columns;
  for_each_or_serial(for_each, n, [&](std::size_t a) {
    for (std::size_t b = 0; b < n; ++b) {
      // a is the destination's plane: y for columns, x for planes.
      const std::size_t from = (b * n + a) * row, to = (a * n + b) * row;
      if (to_columns)
        std::copy_n(planes + from, row, columns + to);
      else
        std::copy_n(columns + from, row, planes + to);
    }
  });
}

// Density -> potential in this rank's planes, ghosts included.
void PeriodicMesh::solve(const ForEach& for_each) {
  const int n = n_;
  const std::size_t row = 2 * static_cast<std::size_t>(n / 2 + 1);
  const double cell = box_ / n;
  const double density_unit = fixed_unit_ / (cell * cell * cell);
  const auto own = static_cast<std::size_t>(nx_);
  // Each plane's arithmetic is its own, so the planes go in parallel with the same bits.
  for_each_or_serial(for_each, own, [&](std::size_t l) {
    double* p = plane(static_cast<int>(l));
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        p[static_cast<std::size_t>(j) * row + static_cast<std::size_t>(k)] =
            static_cast<double>(fixed_[(l * n + static_cast<std::size_t>(j)) * n + static_cast<std::size_t>(k)]) *
            density_unit;
    fftw_execute_dft_r2c(fft_->plane_forward, p, reinterpret_cast<fftw_complex*>(p));
  });
  transpose(true, for_each);
  const std::size_t nk = static_cast<std::size_t>(n / 2 + 1);
  for_each_or_serial(for_each, own, [&](std::size_t jl) {
    auto* c = reinterpret_cast<fftw_complex*>(fft_->columns) + jl * static_cast<std::size_t>(n) * nk;
    fftw_execute_dft(fft_->line_forward, c, c);
    const double* g = &green_[jl * static_cast<std::size_t>(n) * nk];
    for (std::size_t m = 0; m < static_cast<std::size_t>(n) * nk; ++m) {
      c[m][0] *= g[m];
      c[m][1] *= g[m];
    }
    fftw_execute_dft(fft_->line_backward, c, c);
  });
  transpose(false, for_each);
  for_each_or_serial(for_each, own, [&](std::size_t l) {
    double* p = plane(static_cast<int>(l));
    fftw_execute_dft_c2r(fft_->plane_backward, reinterpret_cast<fftw_complex*>(p), p);
  });
  const std::size_t plane_size = plane_doubles();
  if (slabs_) {
    slabs_->fill_ghost_planes(plane(-kGhostBefore), plane_size, kGhostBefore, kGhostAfter);
  } else {
    for (int g = -kGhostBefore; g < 0; ++g) std::copy_n(plane(g + n), plane_size, plane(g));
    for (int g = n; g < n + kGhostAfter; ++g) std::copy_n(plane(g - n), plane_size, plane(g));
  }
}

void PeriodicMesh::compute(std::span<const Vec3> positions, std::span<const double> masses,
                           std::span<Vec3> acceleration, std::span<double> potential, const ForEach& for_each) {
  const std::size_t count = positions.size();
  if (masses.size() != count || acceleration.size() != count || potential.size() != count)
    throw std::invalid_argument("PeriodicMesh::compute: positions, masses and outputs differ in length");
  assign(positions, masses, for_each);
  solve(for_each);
  std::fill(acceleration.begin(), acceleration.end(), Vec3{});
  std::fill(potential.begin(), potential.end(), 0.0);
  interpolate(positions, masses,
              [&](std::size_t p, const Vec3& a, double phi) {
                acceleration[p] = a;
                potential[p] = phi;
              },
              background_potential(), for_each);
  if (slabs_) {
    // Every particle was interpolated by one rank; the others left it +0.0.
    slabs_->combine_bits(std::span<double>(reinterpret_cast<double*>(acceleration.data()), 3 * count));
    slabs_->combine_bits(potential);
  }
}

void PeriodicMesh::set_round_bytes(std::size_t bytes) {
  round_particles_ = std::max<std::size_t>(1, bytes / (sizeof(Vec3) + sizeof(double) + sizeof(std::uint64_t)));
}

void PeriodicMesh::compute_owned(const Sources& sources, const ForceSink& store, const ForEach& for_each) {
  const std::size_t count = sources.count;
  if (!slabs_) {
    std::vector<Vec3> x(count);
    std::vector<double> m(count);
    for (std::size_t p = 0; p < count; ++p) {
      x[p] = sources.position(p);
      m[p] = sources.mass(p);
    }
    assign(x, m, for_each);
    solve(for_each);
    interpolate(x, m, store, background_potential(), for_each);
    return;
  }
  // The fixed-point unit from every rank's masses, as one rank would find it from all of them.
  MassRange range = mass_range(count, sources.mass);
  const double lightest = slabs_->min(range.min > 0.0 ? range.min : std::numeric_limits<double>::infinity());
  range.min = std::isfinite(lightest) ? lightest : 0.0;
  range.max = slabs_->max(range.max);
  range.count = slabs_->sum(range.count);
  const int n = n_;
  const auto planes = static_cast<std::size_t>(n);
  const double cell_inv = n / box_;
  const auto ranks = static_cast<std::size_t>(slabs_->ranks());
  // This rank's particles ordered by the plane below their cloud (that plane's rank
  // interpolates them; the next plane's rank takes a share of their mass too).
  std::vector<std::size_t> from(planes + 1, 0);
  std::vector<std::int64_t> per_plane(planes, 0);
  std::vector<std::size_t> order(count);
  {
    std::vector<std::int32_t> lower(count);
    for (std::size_t p = 0; p < count; ++p) {
      const Vec3 x = sources.position(p);
      if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
        throw std::invalid_argument("PeriodicMesh: particle " + std::to_string(p) + " has a non-finite position");
      lower[p] = cloud_of(x, box_, cell_inv, n).w[0].lo;
      ++per_plane[static_cast<std::size_t>(lower[p])];
    }
    for (std::size_t l = 0; l < planes; ++l) from[l + 1] = from[l] + static_cast<std::size_t>(per_plane[l]);
    std::vector<std::size_t> fill(from.begin(), from.end() - 1);
    for (std::size_t p = 0; p < count; ++p) order[fill[static_cast<std::size_t>(lower[p])]++] = p;
  }
  // Rounds: each rank's planes cut into runs that hold at most round_particles_ particles of
  // all ranks (a plane at least), the same runs on every rank; round r takes every rank's r-th.
  slabs_->sum(per_plane);
  std::vector<int> round_of(planes, 0);
  int rounds = 0;
  for (int q = 0; q < slabs_->ranks(); ++q) {
    int r = 0;
    std::int64_t held = 0;
    for (int l = slabs_->first_plane(q); l < slabs_->first_plane(q) + slabs_->planes(q); ++l) {
      const std::int64_t c = per_plane[static_cast<std::size_t>(l)];
      if (held > 0 && held + c > static_cast<std::int64_t>(round_particles_)) {
        ++r;
        held = 0;
      }
      round_of[static_cast<std::size_t>(l)] = r;
      held += c;
    }
    if (slabs_->planes(q) > 0) rounds = std::max(rounds, r + 1);
  }
  std::vector<std::int64_t>().swap(per_plane);
  struct Sent {
    Vec3 x;
    double m;
    std::uint64_t p;
  };
  struct Back {
    std::uint64_t p;
    Vec3 acceleration;
    double potential;
  };
  // Round r's records: every particle whose lower plane is in the round to that plane's rank
  // and, with `upper`, to the next plane's where that differs.
  std::vector<std::size_t> counts(ranks), at(ranks);
  auto pack = [&](int r, bool upper) {
    std::fill(counts.begin(), counts.end(), 0);
    for (std::size_t l = 0; l < planes; ++l) {
      if (round_of[l] != r) continue;
      const auto lo = static_cast<std::size_t>(slabs_->owner_of(static_cast<int>(l)));
      const auto hi = static_cast<std::size_t>(slabs_->owner_of(static_cast<int>((l + 1) % planes)));
      counts[lo] += from[l + 1] - from[l];
      if (upper && hi != lo) counts[hi] += from[l + 1] - from[l];
    }
    at[0] = 0;
    for (std::size_t q = 1; q < ranks; ++q) at[q] = at[q - 1] + counts[q - 1] * sizeof(Sent);
    std::vector<char> send(at.back() + counts.back() * sizeof(Sent));
    for (std::size_t l = 0; l < planes; ++l) {
      if (round_of[l] != r) continue;
      const auto lo = static_cast<std::size_t>(slabs_->owner_of(static_cast<int>(l)));
      const auto hi = static_cast<std::size_t>(slabs_->owner_of(static_cast<int>((l + 1) % planes)));
      for (std::size_t k = from[l]; k < from[l + 1]; ++k) {
        const std::size_t p = order[k];
        const Sent record{sources.position(p), sources.mass(p), p};
        std::memcpy(send.data() + at[lo], &record, sizeof record);
        at[lo] += sizeof record;
        if (upper && hi != lo) {
          std::memcpy(send.data() + at[hi], &record, sizeof record);
          at[hi] += sizeof record;
        }
      }
    }
    for (std::size_t& c : counts) c *= sizeof(Sent);
    return send;
  };
  // What came in: positions, masses and (sender, its index) of each record.
  std::vector<Vec3> x_in;
  std::vector<double> m_in;
  std::vector<std::pair<std::uint32_t, std::uint64_t>> origin;
  auto unpack = [&](const std::vector<char>& in) {
    const std::size_t records = in.size() / sizeof(Sent);
    x_in.resize(records);
    m_in.resize(records);
    origin.resize(records);
    std::size_t k = 0;
    for (std::size_t q = 0; q < ranks; ++q)
      for (std::size_t b = 0; b < counts[q]; b += sizeof(Sent), ++k) {
        Sent s;
        std::memcpy(&s, in.data() + (k * sizeof(Sent)), sizeof s);
        x_in[k] = s.x;
        m_in[k] = s.m;
        origin[k] = {static_cast<std::uint32_t>(q), s.p};
      }
  };
  begin_deposit(range);
  for (int r = 0; r < rounds; ++r) {
    unpack(slabs_->exchange(pack(r, true), counts));
    add_masses(x_in, m_in, for_each);
  }
  solve(for_each);
  // The same rounds again, each particle to the rank of its lower plane only, which sends its
  // force back, interpolated straight into its record's place (its offset within its
  // sender's part). Positions travel twice so that no round's records outlive it.
  const double background = background_potential();
  std::vector<std::size_t> place;
  std::size_t forces = 0;
  for (int r = 0; r < rounds; ++r) {
    unpack(slabs_->exchange(pack(r, false), counts));
    std::fill(counts.begin(), counts.end(), 0);
    place.resize(x_in.size());
    for (std::size_t k = 0; k < x_in.size(); ++k) {
      place[k] = counts[origin[k].first];
      counts[origin[k].first] += sizeof(Back);
    }
    at[0] = 0;
    for (std::size_t q = 1; q < ranks; ++q) at[q] = at[q - 1] + counts[q - 1];
    std::vector<char> back(at.back() + counts.back());
    interpolate(x_in, m_in,
                [&](std::size_t k, const Vec3& a, double phi) {
                  const Back record{origin[k].second, a, phi};
                  std::memcpy(back.data() + at[origin[k].first] + place[k], &record, sizeof record);
                },
                background, for_each);
    const std::vector<char> in = slabs_->exchange(std::move(back), counts);
    for (std::size_t b = 0; b < in.size(); b += sizeof(Back)) {
      Back rec;
      std::memcpy(&rec, in.data() + b, sizeof rec);
      if (rec.p >= count) throw std::logic_error("PeriodicMesh::compute_owned: a force came back for no particle");
      store(rec.p, rec.acceleration, rec.potential);
    }
    forces += in.size() / sizeof(Back);
  }
  if (forces != count)
    throw std::logic_error("PeriodicMesh::compute_owned: " + std::to_string(forces) + " forces came back for " +
                           std::to_string(count) + " particles");
}

template <class Store>
void PeriodicMesh::interpolate(std::span<const Vec3> positions, std::span<const double> masses, const Store& store,
                               double background, const ForEach& for_each) {
  const std::size_t count = positions.size();
  const double self = G_ / (std::sqrt(std::numbers::pi) * r_s_);

  const int n = n_, nx = nx_, x0 = x0_;
  const std::size_t row = 2 * static_cast<std::size_t>(n / 2 + 1);
  const double cell_inv = n / box_;
  // The fourth-order difference of the potential along each axis at the nodes of local plane
  // l, three per node: each node is read by the clouds of many particles, and each cloud
  // reads eight nodes' three.
  const auto plane_nodes = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  auto gradient_of = [&](int l, double* out) {
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t node = static_cast<std::size_t>(j) * n + static_cast<std::size_t>(k);
        for (int d = 0; d < 3; ++d) {
          auto at = [&](int shift) {
            int ii = l, jj = j, kk = k;
            (d == 0 ? ii : d == 1 ? jj : kk) += shift;
            return plane(ii)[static_cast<std::size_t>(wrap_index(jj, n)) * row + static_cast<std::size_t>(wrap_index(kk, n))];
          };
          out[3 * node + static_cast<std::size_t>(d)] = (8.0 * (at(1) - at(-1)) - (at(2) - at(-2))) * (cell_inv / 12.0);
        }
      }
  };
  if (nx <= 0) return;  // a rank without planes interpolates no particle
  // The particles by their lower plane (the rank of that plane interpolates them), so that a
  // run of planes is taken in one task holding the gradient of two planes at a time, not of
  // the whole slab (three doubles a node, once the largest item of a mesh step's memory).
  std::vector<std::int32_t> lower(count);
  for_each_particle(for_each, count, [&](std::size_t p) {
    const int lo = cloud_of(positions[p], box_, cell_inv, n).w[0].lo - x0;
    lower[p] = lo >= 0 && lo < nx ? lo : nx;
  });
  std::vector<std::size_t> start(static_cast<std::size_t>(nx) + 2, 0);
  for (const std::int32_t l : lower) ++start[static_cast<std::size_t>(l) + 1];
  for (std::size_t l = 1; l < start.size(); ++l) start[l] += start[l - 1];
  std::vector<std::size_t> order(start[static_cast<std::size_t>(nx)]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t p = 0; p < count; ++p)
      if (lower[p] < nx) order[fill[static_cast<std::size_t>(lower[p])]++] = p;
  }
  std::vector<std::int32_t>().swap(lower);
  const int runs = (nx + kGradientRun - 1) / kGradientRun;
  for_each_or_serial(for_each, static_cast<std::size_t>(runs), [&](std::size_t r) {
    const int first = static_cast<int>(r) * kGradientRun, end = std::min(nx, first + kGradientRun);
    // A round of compute_owned brings the particles of a few planes: the others' runs have
    // no gradient to make.
    if (start[static_cast<std::size_t>(first)] == start[static_cast<std::size_t>(end)]) return;
    std::vector<double> window(2 * 3 * plane_nodes);
    double* below = window.data();
    double* above = below + 3 * plane_nodes;
    gradient_of(first, below);
    for (int l = first; l < end; ++l) {
      gradient_of(l + 1, above);  // the top plane's clouds reach the plane above (a ghost for the last)
      for (std::size_t q = start[static_cast<std::size_t>(l)]; q < start[static_cast<std::size_t>(l) + 1]; ++q) {
        const std::size_t p = order[q];
        Vec3 acc;
        double pot = 0.0;
        const Cloud cloud = cloud_of(positions[p], box_, cell_inv, n);
        for_each_cloud_node(cloud, n, [&](int i, int j, int k, double weight) {
          const bool at_lower = i == cloud.w[0].lo;
          const double* g = (at_lower ? below : above) + 3 * (static_cast<std::size_t>(j) * n + static_cast<std::size_t>(k));
          for (int d = 0; d < 3; ++d) acc[d] -= weight * g[d];
          pot += weight * plane(at_lower ? l : l + 1)[static_cast<std::size_t>(j) * row + static_cast<std::size_t>(k)];
        });
        store(p, acc, pot + background + self * masses[p]);
      }
      std::swap(below, above);
    }
  });
}

}  // namespace fountain::gravity
