// The particles of a neighbour cell that can reach a cell, gathered into compact arrays.
#pragma once
#include <cstddef>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::hydro {

// Positions (as the periodic image nearest the target cell) and indices of the candidate
// neighbours, so the inner loops scan short contiguous arrays.
struct NeighbourBlock {
  std::vector<double> x, y, z;
  std::vector<std::size_t> index;

  void clear() { x.clear(); y.clear(); z.clear(); index.clear(); }
  void add(const Vec3& p, std::size_t i) {
    x.push_back(p.x);
    y.push_back(p.y);
    z.push_back(p.z);
    index.push_back(i);
  }
  std::size_t size() const { return index.size(); }
};

// Axis-aligned box of the active particles of a cell.
struct ActiveBox {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  double h_max = 0.0;
  bool empty = true;

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
