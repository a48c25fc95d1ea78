// The particles of a neighbour cell that can reach a cell, gathered into compact arrays.
#pragma once
#include <cstddef>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::hydro {

// Positions (as the periodic image nearest the target cell) and indices of the candidate
// neighbours, so the inner loops scan short contiguous arrays.
struct NeighbourBlock {
  std::vector<double> x, y, z, h2;
  std::vector<std::size_t> index;
  std::vector<double> r2;  // scratch: squared distances to the particle being updated

  void clear() { x.clear(); y.clear(); z.clear(); h2.clear(); index.clear(); }
  void add(const Vec3& p, double h, std::size_t i) {
    x.push_back(p.x);
    y.push_back(p.y);
    z.push_back(p.z);
    h2.push_back(h * h);
    index.push_back(i);
  }
  std::size_t size() const { return index.size(); }

  // Squared distances from p to every candidate, in a loop the compiler can vectorise.
  void distances_to(const Vec3& p) {
    const std::size_t n = size();
    r2.resize(n);
    const double* bx = x.data();
    const double* by = y.data();
    const double* bz = z.data();
    double* out = r2.data();
    for (std::size_t k = 0; k < n; ++k) {
      const double dx = p.x - bx[k], dy = p.y - by[k], dz = p.z - bz[k];
      out[k] = dx * dx + dy * dy + dz * dz;
    }
  }
};

// Axis-aligned box of the active particles of a cell.
struct ActiveBox {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  double h_max = 0.0;
  bool empty = true;

  ActiveBox() = default;
  ActiveBox(const Vec3& l, const Vec3& u, double h) : lo(l), hi(u), h_max(h), empty(h < 0.0) {}

  void add(const Vec3& p, double h) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = p[k] < lo[k] ? p[k] : lo[k];
      hi[k] = p[k] > hi[k] ? p[k] : hi[k];
    }
    h_max = h > h_max ? h : h_max;
    empty = false;
  }
  Vec3 centre() const { return (lo + hi) * 0.5; }
  // Squared distance from p to the box.
  double distance2(const Vec3& p) const {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double d = p[k] < lo[k] ? lo[k] - p[k] : (p[k] > hi[k] ? p[k] - hi[k] : 0.0);
      d2 += d * d;
    }
    return d2;
  }
};

}  // namespace fountain::hydro
