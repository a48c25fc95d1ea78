// The particles of a neighbour cell that can reach a cell, gathered into compact arrays.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "core/ScratchArray.hpp"
#include "core/Vec3.hpp"
#include "hydro/NeighbourScan.hpp"

namespace fountain::hydro {

// Positions (as the periodic image nearest the target cell) and indices of the candidate
// neighbours, so the inner loops scan short contiguous arrays.
struct NeighbourBlock {
  ScratchArray<double> x, y, z, h2;
  ScratchArray<std::size_t> index;
  ScratchArray<double> r2;        // scratch of within(): squared distances to the particle being updated
  ScratchArray<std::uint32_t> hit;  // scratch of within(): the candidates within reach of that particle

  // Empties the block and makes room for `capacity` candidates: add() does not check, so
  // the callers that fill a block know how many candidates they can add at most.
  void reset(std::size_t capacity) {
    n_ = 0;
    for (auto* v : {&x, &y, &z, &h2}) v->ensure(capacity);
    index.ensure(capacity);
  }
  void add(const Vec3& p, double h2_value, std::size_t i) {
    x[n_] = p.x;
    y[n_] = p.y;
    z[n_] = p.z;
    h2[n_] = h2_value;
    index[n_] = i;
    ++n_;
  }
  std::size_t size() const { return n_; }

  // Appends the candidates of `in` (n of them) that scan_near_box keeps; the block must have
  // room for them and kScanSlack more.
  void append_near(const CandidateView& in, std::size_t n, const Vec3& lo, const Vec3& hi, double reach2,
                   bool own_h_reaches) {
    n_ += scan_near_box(in, n, lo, hi, reach2, own_h_reaches,
                        {x.data() + n_, y.data() + n_, z.data() + n_, h2.data() + n_, index.data() + n_});
  }

  CandidateView view() const { return {x.data(), y.data(), z.data(), h2.data(), index.data()}; }
  // Keeps the candidates of `block` that scan_near_box keeps.
  void select_from(const NeighbourBlock& block, const Vec3& lo, const Vec3& hi, double reach2, bool own_h_reaches) {
    reset(block.size() + kScanSlack);
    append_near(block.view(), block.size(), lo, hi, reach2, own_h_reaches);
  }

  // Fills `hit` with the candidates closer to p than `reach2` (squared) or, when
  // `own_h_reaches`, than their own h, and r2 with every candidate's squared distance to p.
  std::size_t within(const Vec3& p, double reach2, bool own_h_reaches) {
    const std::size_t n = size();
    r2.ensure(n);
    hit.ensure(n + kScanSlack);
    return scan_within(x.data(), y.data(), z.data(), h2.data(), n, p, reach2, own_h_reaches, r2.data(), hit.data());
  }

 private:
  std::size_t n_ = 0;
};

// Axis-aligned box of the active particles of a cell or of a group of particles.
struct ActiveBox {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  double h_max = 0.0;
  bool empty = true;

  ActiveBox() = default;
  ActiveBox(const Vec3& l, const Vec3& u, double h) : lo(l), hi(u), h_max(h), empty(h < 0.0) {}

  void add(const Vec3& p, double h) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    h_max = std::max(h_max, h);
    empty = false;
  }
  Vec3 centre() const { return (lo + hi) * 0.5; }
  // Squared distance between this box and another.
  double distance2(const ActiveBox& o) const {
    const double dx = std::max(0.0, std::max(o.lo.x - hi.x, lo.x - o.hi.x));
    const double dy = std::max(0.0, std::max(o.lo.y - hi.y, lo.y - o.hi.y));
    const double dz = std::max(0.0, std::max(o.lo.z - hi.z, lo.z - o.hi.z));
    return dx * dx + dy * dy + dz * dz;
  }
  // Squared distance from p to the box (written per axis: this is a hot loop).
  double distance2(const Vec3& p) const {
    const double dx = std::max(0.0, std::max(lo.x - p.x, p.x - hi.x));
    const double dy = std::max(0.0, std::max(lo.y - p.y, p.y - hi.y));
    const double dz = std::max(0.0, std::max(lo.z - p.z, p.z - hi.z));
    return dx * dx + dy * dy + dz * dz;
  }
};

// Copies into `near` the candidates of `block` that can reach a particle in `box`: closer to the
// box than its largest h (density: gather) or, when `own_h_reaches`, than their own h too (force).
inline void select_near(const NeighbourBlock& block, const ActiveBox& box, bool own_h_reaches, NeighbourBlock& near) {
  near.select_from(block, box.lo, box.hi, box.h_max * box.h_max, own_h_reaches);
}

}  // namespace fountain::hydro
