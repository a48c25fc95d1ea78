// Gaussian white noise of unit variance, one value per cell of a level's grid, from a counter-based generator: the same for any thread or rank count.
#pragma once
#include <cmath>
#include <cstdint>
#include <numbers>

namespace fountain::ics {

// SplitMix64's finaliser: a bijection of 64-bit words that scrambles every bit.
inline std::uint64_t mix64(std::uint64_t y) {
  y += 0x9E3779B97F4A7C15ull;
  y = (y ^ (y >> 30)) * 0xBF58476D1CE4E5B9ull;
  y = (y ^ (y >> 27)) * 0x94D049BB133111EBull;
  return y ^ (y >> 31);
}

// The noise of cell n = (i N + j) N + k on level `level` (N = 2^level cells per side): a
// Box-Muller pair from two uniform deviates in (0, 1), each drawn from the cell's key alone.
inline double white_noise(std::uint64_t seed, int level, std::uint64_t n) {
  const std::uint64_t key = (seed * 0x100000001B3ull) ^ (static_cast<std::uint64_t>(level) << 58) ^ n;
  constexpr double two53 = 9007199254740992.0;
  const double u1 = (static_cast<double>(mix64(2 * key) >> 11) + 0.5) / two53;
  const double u2 = (static_cast<double>(mix64(2 * key + 1) >> 11) + 0.5) / two53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace fountain::ics
