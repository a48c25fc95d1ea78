// The SPH loops' neighbour scans: candidates within reach of a particle, or near a box.
#pragma once
#include <cstddef>
#include <cstdint>

#include "core/Vec3.hpp"

namespace fountain::hydro {

// Candidates k < n at positions (x, y, z)[k]: stores r2[k] = |p - x_k|^2 for every k and
// lists in `hit`, in increasing order, those with r2 < reach2 or, when `own_h_reaches`,
// r2 < h2[k]. Returns how many. `hit` needs room for n + kScanSlack entries.
std::size_t scan_within(const double* x, const double* y, const double* z, const double* h2, std::size_t n,
                        const Vec3& p, double reach2, bool own_h_reaches, double* r2, std::uint32_t* hit);

inline constexpr std::size_t kScanSlack = 8;

// The same, always on the portable path (tests compare the two).
std::size_t scan_within_portable(const double* x, const double* y, const double* z, const double* h2, std::size_t n,
                                 const Vec3& p, double reach2, bool own_h_reaches, double* r2, std::uint32_t* hit);

// The candidates (x, y, z, h2, index)[k], k < n, closer to the box [lo, hi] than sqrt(reach2)
// or, when `own_h_reaches`, than their own h, copied in order to the `out_` arrays; returns
// how many. Each output array needs room for n + kScanSlack entries.
struct CandidateArrays {
  double *x, *y, *z, *h2;
  std::size_t* index;
};
struct CandidateView {
  const double *x, *y, *z, *h2;
  const std::size_t* index;
};
std::size_t scan_near_box(const CandidateView& in, std::size_t n, const Vec3& lo, const Vec3& hi, double reach2,
                          bool own_h_reaches, const CandidateArrays& out);
std::size_t scan_near_box_portable(const CandidateView& in, std::size_t n, const Vec3& lo, const Vec3& hi,
                                   double reach2, bool own_h_reaches, const CandidateArrays& out);

// Whether scan_within and scan_near_box take the AVX-512 path on this machine.
bool scan_within_is_avx512();

}  // namespace fountain::hydro
