// Work spread over ranks by slabs of x: the group finders' slabs, and the collectives they exchange particles through.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/Collectives.hpp"
#include "core/PeriodicWrap.hpp"

namespace fountain::groups {

template <class T>
std::vector<char> bytes_of(const std::vector<T>& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<char> out(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(out.data(), v.data(), out.size());
  return out;
}

template <class T>
void append_from(std::span<const char> bytes, std::vector<T>& out) {
  if (bytes.size() % sizeof(T) != 0) throw std::logic_error("friends-of-friends: a message of the wrong length");
  const std::size_t n = bytes.size() / sizeof(T), at = out.size();
  out.resize(at + n);
  if (n > 0) std::memcpy(static_cast<void*>(out.data() + at), bytes.data(), bytes.size());
}

// Every rank's values, one after the other in rank order.
template <class T>
std::vector<T> gather_all(const std::vector<T>& mine, Collectives* ranks) {
  if (ranks == nullptr) return mine;
  std::vector<T> all;
  for (const auto& b : ranks->allgather(bytes_of(mine))) append_from<T>(b, all);
  return all;
}

// to[q] goes to rank q; what every rank sent this one, in rank order (its own to[me] in place).
template <class T>
std::vector<T> exchange(std::vector<std::vector<T>>& to, Collectives* ranks) {
  if (ranks == nullptr) return std::move(to[0]);
  const int me = ranks->rank();
  std::vector<std::vector<char>> out(to.size());
  for (std::size_t q = 0; q < to.size(); ++q)
    if (static_cast<int>(q) != me) {
      out[q] = bytes_of(to[q]);
      std::vector<T>().swap(to[q]);
    }
  const std::vector<std::vector<char>> in = ranks->alltoall(std::move(out));
  std::vector<T> arrived;
  for (std::size_t q = 0; q < to.size(); ++q) {
    if (static_cast<int>(q) == me) arrived.insert(arrived.end(), to[q].begin(), to[q].end());
    else append_from<T>(in[q], arrived);
  }
  return arrived;
}

// Slabs of x with equal particle counts (to a 4096th of the box), one per rank, cut from a
// histogram summed over the ranks: the same slabs however the particles are spread.
class Slabs {
 public:
  // `x`: this rank's particles' x coordinates.
  Slabs(std::span<const double> x, double box, Collectives* ranks);

  int count() const { return static_cast<int>(first_bin_.size()) - 1; }
  double extent() const { return width_; }  // of the slabs together, in x
  int of(double x) const { return slab_of_bin_[static_cast<std::size_t>(bin(x))]; }

  // Whether x lies within `reach` of slab q (nearest images when periodic).
  bool near(double x, int q, double reach) const {
    const int b0 = first_bin_[static_cast<std::size_t>(q)], b1 = first_bin_[static_cast<std::size_t>(q) + 1];
    if (b0 == b1) return false;  // empty
    const double a = lo_ + width_ * b0 / kBins, b = lo_ + width_ * b1 / kBins;
    const double xf = box_ > 0.0 ? wrap_into_box(x, box_) : x;
    if (xf >= a && xf <= b) return true;
    if (box_ > 0.0) {
      auto ahead = [&](double d) { return d - box_ * std::floor(d / box_); };
      return std::min(ahead(a - xf), ahead(xf - b)) < reach;
    }
    return (xf < a ? a - xf : xf - b) < reach;
  }

  // For x in slab q: its distance to the nearest edge of the slab (infinite for a lone
  // periodic slab, which has none). A ball about x of radius r < depth + w holds no particle
  // that is not in the slab or within w of it.
  double depth(double x, int q) const {
    if (count() == 1) return std::numeric_limits<double>::infinity();
    const double a = lo_ + width_ * first_bin_[static_cast<std::size_t>(q)] / kBins;
    const double b = lo_ + width_ * first_bin_[static_cast<std::size_t>(q) + 1] / kBins;
    const double xf = box_ > 0.0 ? wrap_into_box(x, box_) : x;
    if (box_ <= 0.0) {
      // An open box's outer slabs reach to infinity on their outer side.
      const double left = q == 0 ? std::numeric_limits<double>::infinity() : xf - a;
      const double right = q == count() - 1 ? std::numeric_limits<double>::infinity() : b - xf;
      return std::max(0.0, std::min(left, right));
    }
    return std::max(0.0, std::min(xf - a, b - xf));
  }

 private:
  static constexpr int kBins = 4096;
  int bin(double x) const {
    const double xf = box_ > 0.0 ? wrap_into_box(x, box_) : x;
    const double b = std::floor((xf - lo_) / width_ * kBins);
    return static_cast<int>(std::clamp(b, 0.0, static_cast<double>(kBins - 1)));
  }
  double box_ = 0.0, lo_ = 0.0, width_ = 1.0;
  std::vector<int> slab_of_bin_, first_bin_;
};

// A count summed over every rank (this rank's alone when ranks is null).
inline std::uint64_t count_over_ranks(std::uint64_t mine, Collectives* ranks) {
  std::uint64_t total = 0;
  for (std::uint64_t n : gather_all(std::vector<std::uint64_t>{mine}, ranks)) total += n;
  return total;
}

// Every rank's values on rank 0, in rank order; the other ranks get none (alone: `mine`).
template <class T>
std::vector<T> on_rank_zero(std::vector<T> mine, Collectives* ranks) {
  if (ranks == nullptr) return mine;
  std::vector<std::vector<T>> to(static_cast<std::size_t>(ranks->size()));
  to[0] = std::move(mine);
  return exchange(to, ranks);
}

// Slabs for `records` (each with a position x, an id and an origin), and the records sent to
// their slabs' ranks: on return each rank holds its slab's, by (id, origin).
template <class Record>
Slabs into_slabs(std::vector<Record>& records, double box, Collectives* ranks) {
  std::vector<double> x(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) x[i] = records[i].x.x;
  Slabs slabs(x, box, ranks);
  std::vector<double>().swap(x);
  if (ranks != nullptr) {
    std::vector<std::vector<Record>> to(static_cast<std::size_t>(ranks->size()));
    for (const Record& r : records) to[static_cast<std::size_t>(slabs.of(r.x.x))].push_back(r);
    std::vector<Record>().swap(records);
    records = exchange(to, ranks);
  }
  std::sort(records.begin(), records.end(),
            [](const Record& a, const Record& b) { return a.id < b.id || (a.id == b.id && a.origin < b.origin); });
  return slabs;
}

}  // namespace fountain::groups
