#include "gravity/EwaldSummation.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "gravity/GravityKernel.hpp"

namespace fountain::gravity {

namespace {

constexpr double kPi = std::numbers::pi;
const double kTwoOverSqrtPi = 2.0 / std::sqrt(kPi);

// One wave of the Fourier sum, in units of the box: k = 2 pi h, with the weight
// exp(-k^2 / 4 alpha^2) / k^2 of the pair of waves +h and -h (hence the factor 2).
struct Wave {
  Vec3 k;
  double weight;
};

std::vector<Wave> waves(const EwaldSettings& s) {
  if (!(s.alpha > 0.0) || !(s.real_reach > 0.0) || s.fourier_h2 < 1)
    throw std::invalid_argument("Ewald summation: alpha, real_reach and fourier_h2 must be positive");
  std::vector<Wave> out;
  const int h_max = static_cast<int>(std::floor(std::sqrt(static_cast<double>(s.fourier_h2))));
  for (int hx = 0; hx <= h_max; ++hx)
    for (int hy = -h_max; hy <= h_max; ++hy)
      for (int hz = -h_max; hz <= h_max; ++hz) {
        // One of each pair +h, -h: the first nonzero component positive.
        if (hx == 0 && (hy < 0 || (hy == 0 && hz <= 0))) continue;
        if (hx * hx + hy * hy + hz * hz > s.fourier_h2) continue;
        const Vec3 k{2.0 * kPi * hx, 2.0 * kPi * hy, 2.0 * kPi * hz};
        const double k2 = dot(k, k);
        out.push_back({k, 2.0 * std::exp(-k2 / (4.0 * s.alpha * s.alpha)) / k2});
      }
  return out;
}

// (erf(y) - 2 y exp(-y^2) / sqrt(pi)) / y^3: the nearest image's Newtonian force minus its
// real-space Ewald term, finite at y = 0. Its series is used where the difference cancels.
double smooth_force(double y) {
  if (y < 0.1) {
    const double y2 = y * y;
    // sum over n >= 1 of (-1)^(n+1) 2n y^(2n-2) / (n! (2n+1)), times 2 / sqrt(pi).
    return kTwoOverSqrtPi *
           (2.0 / 3.0 + y2 * (-2.0 / 5.0 + y2 * (1.0 / 7.0 + y2 * (-1.0 / 27.0 + y2 * (1.0 / 132.0)))));
  }
  return (std::erf(y) - kTwoOverSqrtPi * y * std::exp(-y * y)) / (y * y * y);
}

// erf(y) / y, finite at 0.
double smooth_potential(double y) { return y < 1e-8 ? kTwoOverSqrtPi : std::erf(y) / y; }

// The real-space sum at s (units of the box), G = m = 1; with `corrected`, the nearest
// image's term is replaced by that term plus the Newtonian field of that image.
EwaldField real_space(const Vec3& s, const EwaldSettings& set, bool corrected) {
  const double a = set.alpha, reach = set.real_reach;
  const Vec3 nearest{std::nearbyint(s.x), std::nearbyint(s.y), std::nearbyint(s.z)};
  EwaldField out;
  int lo[3] = {}, hi[3] = {};
  for (int d = 0; d < 3; ++d) {
    lo[d] = static_cast<int>(std::ceil(s[d] - reach));
    hi[d] = static_cast<int>(std::floor(s[d] + reach));
  }
  for (int nx = lo[0]; nx <= hi[0]; ++nx)
    for (int ny = lo[1]; ny <= hi[1]; ++ny)
      for (int nz = lo[2]; nz <= hi[2]; ++nz) {
        const Vec3 d = s - Vec3{double(nx), double(ny), double(nz)};
        const double r2 = dot(d, d);
        const double r = std::sqrt(r2);
        const bool is_nearest = nx == nearest.x && ny == nearest.y && nz == nearest.z;
        if (corrected && is_nearest) {
          // Newtonian (+d/r^3, +1/r) plus the Ewald term (-erfc-weighted).
          out.acceleration += (a * a * a * smooth_force(a * r)) * d;
          out.potential += a * smooth_potential(a * r);
          continue;
        }
        if (r > reach) continue;
        const double ar = a * r;
        const double e = std::erfc(ar);
        out.acceleration -= ((e + kTwoOverSqrtPi * ar * std::exp(-ar * ar)) / (r2 * r)) * d;
        out.potential -= e / r;
      }
  out.potential += kPi / (a * a);
  return out;
}

EwaldField field(const Vec3& x, double box, const EwaldSettings& set, bool corrected) {
  if (!(box > 0.0)) throw std::invalid_argument("Ewald summation: box size must be positive");
  const Vec3 s = (1.0 / box) * x;
  EwaldField out = real_space(s, set, corrected);
  for (const Wave& w : waves(set)) {
    const double phase = dot(w.k, s);
    out.acceleration -= (4.0 * kPi * w.weight * std::sin(phase)) * w.k;
    out.potential -= 4.0 * kPi * w.weight * std::cos(phase);
  }
  out.acceleration *= 1.0 / (box * box);
  out.potential *= 1.0 / box;
  return out;
}

}  // namespace

EwaldField ewald_field(const Vec3& x, double box, const EwaldSettings& settings) {
  return field(x, box, settings, false);
}

EwaldField ewald_correction(const Vec3& x, double box, const EwaldSettings& settings) {
  return field(x, box, settings, true);
}

std::vector<Vec3> ewald_accelerations(std::span<const Vec3> positions, std::span<const double> masses,
                                      std::span<const double> softenings, double box, double G,
                                      std::span<const std::size_t> targets) {
  const std::size_t n = positions.size();
  if (masses.size() != n || softenings.size() != n)
    throw std::invalid_argument("ewald_accelerations: positions, masses and softenings differ in length");
  if (!(box > 0.0)) throw std::invalid_argument("ewald_accelerations: box size must be positive");
  for (std::size_t t : targets)
    if (t >= n) throw std::invalid_argument("ewald_accelerations: target " + std::to_string(t) + " out of range");
  // A larger alpha than the single-field default moves work from the (per pair) real-space
  // sum to the (per particle) Fourier sum; both tails stay below 1e-16.
  EwaldSettings set;
  set.alpha = 4.0;
  set.real_reach = 1.55;
  set.fourier_h2 = 64;
  const std::vector<Wave> ws = waves(set);
  const double box_inv = 1.0 / box;

  // Structure factors C_k = sum m cos(k.s), S_k = sum m sin(k.s).
  std::vector<double> c(ws.size(), 0.0), sn(ws.size(), 0.0);
  for (std::size_t w = 0; w < ws.size(); ++w)
    for (std::size_t j = 0; j < n; ++j) {
      const double phase = dot(ws[w].k, box_inv * positions[j]);
      c[w] += masses[j] * std::cos(phase);
      sn[w] += masses[j] * std::sin(phase);
    }

  std::vector<Vec3> out(targets.size());
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const std::size_t i = targets[t];
    Vec3 images;  // the images' and background's part, in units of G / L^2
    for (std::size_t w = 0; w < ws.size(); ++w) {
      const double phase = dot(ws[w].k, box_inv * positions[i]);
      images -= (4.0 * kPi * ws[w].weight * (std::sin(phase) * c[w] - std::cos(phase) * sn[w])) * ws[w].k;
    }
    Vec3 nearest;  // softened nearest-image forces, G = 1, in the caller's units
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;  // its images cancel in pairs: the correction at 0 is 0
      Vec3 d = box_inv * (positions[i] - positions[j]);
      for (int k = 0; k < 3; ++k) d[k] -= std::nearbyint(d[k]);
      images += masses[j] * real_space(d, set, true).acceleration;
      const double r = box * norm(d);
      const double h = pair_spline_length(softenings[i], softenings[j]);
      if (r == 0.0 && h == 0.0) continue;
      nearest -= (masses[j] * softened_pair(r, h).force * box) * d;
    }
    out[t] = G * (nearest + (box_inv * box_inv) * images);
  }
  return out;
}

}  // namespace fountain::gravity
