#include "ics/RotatingSphere.hpp"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "core/Error.hpp"

namespace fountain::ics {

namespace {

// Visits the points offset + d (i, j, k) (integer i, j, k) that lie strictly inside the sphere
// of radius R about the origin, in a fixed order. `offset` is 0 or d/2 in each coordinate.
template <class Visit>
void cubic_ball(double d, double offset, double R, Visit&& visit) {
  const int K = static_cast<int>(std::ceil(R / d)) + 1;
  const double R2 = R * R;
  for (int i = -K; i <= K; ++i)
    for (int j = -K; j <= K; ++j)
      for (int k = -K; k <= K; ++k) {
        const Vec3 p{offset + d * i, offset + d * j, offset + d * k};
        if (dot(p, p) < R2) visit(p);
      }
}

std::size_t count_ball(double d, double offset, double R) {
  std::size_t n = 0;
  cubic_ball(d, offset, R, [&](const Vec3&) { ++n; });
  return n;
}

// The lattice spacing: the nominal d = R (4 pi / (3 N))^(1/3), refined over +-4 % so that the
// DM (unshifted) and gas (shifted by d/2) lattices together hold as nearly 2 N points as
// possible, with the two counts as close to N each as possible.
double choose_spacing(int n, double R) {
  const double d0 = R * std::cbrt(4.0 * M_PI / (3.0 * n));
  constexpr int steps = 400;
  double best_d = d0;
  long best_score = -1;
  for (int s = 0; s <= steps; ++s) {
    // Start from the nominal spacing and walk outwards alternately (ties favour d0).
    const int m = (s + 1) / 2 * (s % 2 ? 1 : -1);
    const double d = d0 * (1.0 + 0.04 * m / (steps / 2));
    const long n_dm = static_cast<long>(count_ball(d, 0.0, R));
    const long n_gas = static_cast<long>(count_ball(d, 0.5 * d, R));
    const long score = std::labs(n_dm + n_gas - 2L * n) * 4 + std::labs(n_dm - n) + std::labs(n_gas - n);
    if (best_score < 0 || score < best_score) {
      best_score = score;
      best_d = d;
    }
  }
  return best_d;
}

// Cubic lattice ball of spacing d (offset 0 or d/2), optionally jittered, stretched from
// uniform density to rho ~ 1/r: r_new = R (r_old/R)^(3/2).
std::vector<Vec3> stretched_ball(double d, double offset, double R, double jitter, std::mt19937_64& rng) {
  std::vector<Vec3> points;
  std::uniform_real_distribution<double> uniform(-0.5, 0.5);
  cubic_ball(d, offset, R, [&](const Vec3& p) { points.push_back(p); });
  if (jitter > 0.0) {
    std::vector<Vec3> kept;
    kept.reserve(points.size());
    for (Vec3 p : points) {
      // Three draws per point, always, so the stream does not depend on which points are kept.
      const double a = uniform(rng), b = uniform(rng), c = uniform(rng);
      p += Vec3{a, b, c} * (jitter * d);
      if (dot(p, p) < R * R) kept.push_back(p);
    }
    points.swap(kept);
  }
  for (Vec3& p : points) {
    const double r = norm(p);
    p *= std::sqrt(r / R);  // |p| becomes R (r/R)^(3/2)
  }
  return points;
}

}  // namespace

double direct_potential_energy(const std::vector<Vec3>& x, const std::vector<double>& m, double G, double eps) {
  const std::size_t n = x.size();
  if (m.size() != n) throw InputError("direct_potential_energy: positions and masses differ in length");
  std::vector<double> px(n), py(n), pz(n);
  for (std::size_t i = 0; i < n; ++i) {
    px[i] = x[i].x;
    py[i] = x[i].y;
    pz[i] = x[i].z;
  }
  const double eps2 = eps * eps;
  std::vector<double> row(n, 0.0);
  // Rows i sum over j > i, so early rows are long: small grains keep the threads balanced.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const double xi = px[i], yi = py[i], zi = pz[i];
      std::size_t j = i + 1;
      double s = 0.0;
#ifdef __SSE2__
      // Two pairs at a time (packed sqrt and divide: the compiler will not vectorise
      // std::sqrt under the default -fmath-errno).
      __m128d acc = _mm_setzero_pd();
      const __m128d vx = _mm_set1_pd(xi), vy = _mm_set1_pd(yi), vz = _mm_set1_pd(zi), ve = _mm_set1_pd(eps2);
      for (; j + 2 <= n; j += 2) {
        const __m128d dx = _mm_sub_pd(_mm_loadu_pd(&px[j]), vx);
        const __m128d dy = _mm_sub_pd(_mm_loadu_pd(&py[j]), vy);
        const __m128d dz = _mm_sub_pd(_mm_loadu_pd(&pz[j]), vz);
        const __m128d r2 = _mm_add_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz)), ve);
        acc = _mm_add_pd(acc, _mm_div_pd(_mm_loadu_pd(&m[j]), _mm_sqrt_pd(r2)));
      }
      double lanes[2];
      _mm_storeu_pd(lanes, acc);
      s = lanes[0] + lanes[1];
#endif
      for (; j < n; ++j) {
        const double dx = px[j] - xi, dy = py[j] - yi, dz = pz[j] - zi;
        s += m[j] / std::sqrt(dx * dx + dy * dy + dz * dz + eps2);
      }
      row[i] = m[i] * s;
    }
  });
  double sum = 0.0;
  for (double r : row) sum += r;
  return -G * sum;
}

RotatingSphereIC rotating_sphere(const RotatingSphereParams& p) {
  const auto bad = [](const std::string& what) { throw InputError("rotating sphere initial conditions: " + what); };
  if (p.particles_per_species < 8) bad(fmt::format("particles per species is {}, need at least 8", p.particles_per_species));
  if (!(p.total_mass > 0.0) || !std::isfinite(p.total_mass)) bad(fmt::format("total mass {} must be positive", p.total_mass));
  if (!(p.radius > 0.0) || !std::isfinite(p.radius)) bad(fmt::format("radius {} must be positive", p.radius));
  if (!(p.spin >= 0.0) || !std::isfinite(p.spin)) bad(fmt::format("spin {} must be non-negative", p.spin));
  if (!(p.thermal_fraction > 0.0) || !std::isfinite(p.thermal_fraction))
    bad(fmt::format("thermal fraction {} must be positive (the gas needs u > 0)", p.thermal_fraction));
  if (!(p.gas_fraction > 0.0 && p.gas_fraction < 1.0))
    bad(fmt::format("gas fraction {} must lie strictly between 0 and 1", p.gas_fraction));
  if (!(p.G > 0.0) || !std::isfinite(p.G)) bad(fmt::format("G = {} must be positive", p.G));
  if (!(p.potential_softening >= 0.0)) bad("potential softening must be non-negative");
  if (!(p.jitter >= 0.0 && p.jitter <= 1.0)) bad(fmt::format("jitter {} must lie in [0, 1]", p.jitter));
  if (!(p.smoothing_neighbours >= 0.0)) bad("smoothing neighbours must be non-negative");

  const double R = p.radius, M = p.total_mass;
  RotatingSphereIC ic;
  const double d = choose_spacing(p.particles_per_species, R);
  ic.lattice_spacing = d;

  std::mt19937_64 rng(p.seed);
  const std::vector<Vec3> x_dm = stretched_ball(d, 0.0, R, p.jitter, rng);
  const std::vector<Vec3> x_gas = stretched_ball(d, 0.5 * d, R, p.jitter, rng);
  const std::size_t n_dm = x_dm.size(), n_gas = x_gas.size();

  const double m_gas_total = p.gas_fraction * M;
  const double m_dm = (M - m_gas_total) / static_cast<double>(n_dm);
  const double m_gas = m_gas_total / static_cast<double>(n_gas);

  // All particles in one list (gas first) for the sums.
  std::vector<Vec3> x_all;
  std::vector<double> m_all;
  x_all.reserve(n_gas + n_dm);
  m_all.reserve(n_gas + n_dm);
  for (const Vec3& x : x_gas) x_all.push_back(x), m_all.push_back(m_gas);
  for (const Vec3& x : x_dm) x_all.push_back(x), m_all.push_back(m_dm);

  // A perfect lattice is symmetric about the origin; a jittered one is recentred.
  Vec3 shift{};
  if (p.jitter > 0.0) {
    Vec3 mx{};
    double msum = 0.0;
    for (std::size_t i = 0; i < x_all.size(); ++i) mx += m_all[i] * x_all[i], msum += m_all[i];
    shift = mx * (1.0 / msum);
    for (Vec3& x : x_all) x -= shift;
  }

  // Energies of the actual particle set.
  const double W = direct_potential_energy(x_all, m_all, p.G, p.potential_softening * R);
  double I_z = 0.0;
  for (std::size_t i = 0; i < x_all.size(); ++i) I_z += m_all[i] * (x_all[i].x * x_all[i].x + x_all[i].y * x_all[i].y);
  const double u = p.thermal_fraction * std::abs(W) / M;
  const double U = u * m_gas_total;

  // lambda = omega I_z |W + U + omega^2 I_z / 2|^(1/2) / (G M^(5/2)), solved for omega by
  // fixed-point iteration (the map's slope at the root is K_rot/|E| ~ 0.04 for lambda = 0.1).
  const double C = p.spin * p.G * std::pow(M, 2.5) / I_z;
  double omega = 0.0;
  int it = 0;
  for (; it < 200; ++it) {
    const double E = W + U + 0.5 * omega * omega * I_z;
    if (!(E < 0.0))
      bad(fmt::format("no solid-body rotation gives spin {} with thermal fraction {}: the sphere would be unbound",
                      p.spin, p.thermal_fraction));
    const double next = C / std::sqrt(-E);
    const bool done = std::abs(next - omega) <= 1e-15 * next;
    omega = next;
    if (done) break;
  }
  if (it == 200) bad(fmt::format("the rotation for spin {} did not converge (spin too large?)", p.spin));

  ic.omega = omega;
  ic.u = u;
  ic.potential_energy = W;
  ic.rotational_energy = 0.5 * omega * omega * I_z;
  ic.thermal_energy = U;
  ic.angular_momentum = omega * I_z;
  ic.spin = ic.angular_momentum * std::sqrt(std::abs(W + ic.rotational_energy + U)) / (p.G * std::pow(M, 2.5));
  ic.iterations = it + 1;

  const auto velocity = [&](const Vec3& x) { return Vec3{-omega * x.y, omega * x.x, 0.0}; };

  GasParticles& gas = ic.gas;
  gas.resize(n_gas);
  const double rho_coeff = m_gas_total / (2.0 * M_PI * R * R);  // rho_gas = rho_coeff / r
  for (std::size_t i = 0; i < n_gas; ++i) {
    const Vec3 x = x_all[i];
    gas.id[i] = i + 1;
    gas.mass[i] = m_gas;
    gas.x[i] = x;
    gas.v_full[i] = gas.v[i] = velocity(x);
    gas.u_full[i] = gas.u[i] = u;
    double h = 0.0;
    if (p.smoothing_neighbours > 0.0) {
      // At the centre use a tenth of the lattice spacing as the radius (no point sits there).
      const double r = std::max(norm(x), 0.1 * d);
      h = std::cbrt(3.0 * p.smoothing_neighbours * m_gas * r / (4.0 * M_PI * rho_coeff));
    }
    gas.h[i] = h;
    gas.time_bin[i] = 0;
  }

  CollisionlessParticles& dm = ic.dm;
  dm.resize(n_dm);
  for (std::size_t i = 0; i < n_dm; ++i) {
    const Vec3 x = x_all[n_gas + i];
    dm.id[i] = n_gas + i + 1;
    dm.mass[i] = m_dm;
    dm.x[i] = x;
    dm.v_full[i] = dm.v[i] = velocity(x);
  }
  return ic;
}

}  // namespace fountain::ics
