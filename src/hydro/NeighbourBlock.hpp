// The particles of a neighbour cell that can reach a cell, gathered into compact arrays.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "core/Vec3.hpp"

namespace fountain::hydro {

// A grow-only array whose elements start uninitialised. A block is sized for the most
// candidates a neighbourhood could hold, but only the pages actually written become resident
// (a zero-filled std::vector touched all of them: ~20 B per particle of peak memory on two
// threads in the 250k Sedov run).
template <class T>
class ScratchArray {
 public:
  // Room for n elements; the contents are not kept when it grows.
  void ensure(std::size_t n) {
    if (n <= capacity_) return;
    data_.reset(new T[n]);
    capacity_ = n;
  }
  T& operator[](std::size_t k) { return data_[k]; }
  const T& operator[](std::size_t k) const { return data_[k]; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t capacity_ = 0;
};

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
  // Adds the candidate when `keep`, without a branch (the filters that call this keep about
  // half of what they see, in no pattern a branch predictor could learn).
  void add_if(bool keep, const Vec3& p, double h2_value, std::size_t i) {
    x[n_] = p.x;
    y[n_] = p.y;
    z[n_] = p.z;
    h2[n_] = h2_value;
    index[n_] = i;
    n_ += keep ? 1 : 0;
  }
  std::size_t size() const { return n_; }

  // Squared distances from p to every candidate, in a loop the compiler can vectorise.
  void distances_to(const Vec3& p) {
    const std::size_t n = size();
    r2.ensure(n);
    hit.ensure(n);
    const double* bx = x.data();
    const double* by = y.data();
    const double* bz = z.data();
    double* out = r2.data();
    for (std::size_t k = 0; k < n; ++k) {
      const double dx = p.x - bx[k], dy = p.y - by[k], dz = p.z - bz[k];
      out[k] = dx * dx + dy * dy + dz * dz;
    }
  }

  // Fills `hit` with the candidates closer to p than `reach2` (squared) or, when
  // `own_h_reaches`, than their own h; without branches, so the scan stays cheap.
  std::size_t within(const Vec3& p, double reach2, bool own_h_reaches) {
    distances_to(p);
    const std::size_t n = size();
    // Two halves compacted side by side (independent counters), then joined: the same list
    // in the same order, with half the loop-carried dependency (measured: 5% of a Sod step;
    // four quarters were slower).
    const std::size_t half = n / 2;
    std::uint32_t* lo = hit.data();
    std::uint32_t* hi = hit.data() + half;
    std::size_t m0 = 0, m1 = 0;
    auto keep = [&](std::size_t k) {
      return static_cast<std::size_t>((r2[k] < reach2) | (own_h_reaches & (r2[k] < h2[k])));
    };
    for (std::size_t k = 0; k < half; ++k) {
      lo[m0] = static_cast<std::uint32_t>(k);
      hi[m1] = static_cast<std::uint32_t>(half + k);
      m0 += keep(k);
      m1 += keep(half + k);
    }
    if (n % 2 == 1) {
      hi[m1] = static_cast<std::uint32_t>(n - 1);
      m1 += keep(n - 1);
    }
    if (m0 < half) std::copy(hi, hi + m1, lo + m0);
    return m0 + m1;
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
inline void select_near(const NeighbourBlock& block, const ActiveBox& box, bool own_h_reaches,
                        NeighbourBlock& near) {
  near.reset(block.size());
  const double reach2 = box.h_max * box.h_max;
  for (std::size_t k = 0; k < block.size(); ++k) {
    const double d2 = box.distance2({block.x[k], block.y[k], block.z[k]});
    near.add_if((d2 < reach2) | (own_h_reaches & (d2 < block.h2[k])), {block.x[k], block.y[k], block.z[k]}, block.h2[k],
                block.index[k]);
  }
}

}  // namespace fountain::hydro
