// The exact sum of any doubles, whatever their order or their split between threads and ranks, rounded once at the end.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace fountain {

// A fixed-point number wide enough for every finite double (from 2^-1074 to 2^1024) with
// room for 2^30 additions between carries: a double adds in exactly, so the total depends on
// nothing but the values added. Sums taken apart (threads, ranks) combine exactly with add().
// value() is deterministic (the same total gives the same double); it is the exact total
// rounded to 64 significant bits and then to a double. Non-finite values give what a double
// sum would: NaN with any NaN (or both infinities), else the infinity added.
class ExactSum {
 public:
  static constexpr int kLimbs = 68;          // of 32 bits: 2176 bits, past 2^1024 with room for carries
  static constexpr int kLowestExponent = -1074;

  void add(double x) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &x, sizeof bits);
    const bool negative = (bits >> 63) != 0;
    const auto biased = static_cast<int>((bits >> 52) & 0x7ff);
    std::uint64_t n = bits & ((std::uint64_t{1} << 52) - 1);
    if (biased == 0x7ff) {  // as a double sum would: NaN poisons it, infinities dominate it
      special_ |= n != 0 ? kNan : (negative ? kMinusInfinity : kPlusInfinity);
      return;
    }
    if (biased == 0 && n == 0) return;  // either zero
    // x = n 2^(p - 1074): a subnormal's n is its fraction (p = 0), a normal one's has the
    // implicit leading bit.
    int p = 0;
    if (biased > 0) {
      n |= std::uint64_t{1} << 52;
      p = biased - 1;
    }
    // n spans at most three limbs from limb k (k + 2 <= 65 for the largest doubles).
    const auto magnitude = static_cast<unsigned __int128>(n) << (p % 32);
    const auto k = static_cast<std::size_t>(p / 32);
    std::int64_t parts[3] = {static_cast<std::int64_t>(static_cast<std::uint32_t>(magnitude)),
                             static_cast<std::int64_t>(static_cast<std::uint32_t>(magnitude >> 32)),
                             static_cast<std::int64_t>(static_cast<std::uint32_t>(magnitude >> 64))};
    if (negative)
      for (std::int64_t& part : parts) part = -part;
    limbs_[k] += parts[0];
    limbs_[k + 1] += parts[1];
    limbs_[k + 2] += parts[2];
    if (++pending_ == kAddsBetweenCarries) carry();
  }

  void add(const ExactSum& other) {
    ExactSum o = other;
    o.carry();
    carry();
    for (std::size_t j = 0; j < limbs_.size(); ++j) limbs_[j] += o.limbs_[j];
    carry();
    special_ |= o.special_;
  }

  double value() const {
    if (special_ != 0) {
      if ((special_ & kNan) != 0 || special_ == (kPlusInfinity | kMinusInfinity))
        return std::numeric_limits<double>::quiet_NaN();
      return special_ == kPlusInfinity ? std::numeric_limits<double>::infinity()
                                       : -std::numeric_limits<double>::infinity();
    }
    ExactSum s = *this;
    s.carry();
    // After carrying, every limb but the last is in [0, 2^32); the last holds the sign.
    const bool negative = s.limbs_.back() < 0;
    if (negative) s.negate();
    int top = kLimbs - 1;
    while (top >= 0 && s.limbs_[static_cast<std::size_t>(top)] == 0) --top;
    if (top < 0) return 0.0;
    // The top three limbs (at most 96 bits), with a sticky bit for anything below them.
    unsigned __int128 head = 0;
    int low = top;
    for (int j = 0; j < 3 && low >= 0; ++j, --low)
      head = (head << 32) | static_cast<std::uint64_t>(s.limbs_[static_cast<std::size_t>(low)]);
    bool sticky = false;
    for (int j = low; j >= 0; --j) sticky = sticky || s.limbs_[static_cast<std::size_t>(j)] != 0;
    // Keep 64 significant bits (and the sticky bit below them), then round to a double.
    int shift = 0;
    while ((head >> 64) != 0) {
      sticky = sticky || (head & 1) != 0;
      head >>= 1;
      ++shift;
    }
    auto bits = static_cast<std::uint64_t>(head);
    if (sticky) bits |= 1;  // below the double's 53 bits whenever the head has more than 53
    const double v = std::ldexp(static_cast<double>(bits), shift + 32 * (low + 1) + kLowestExponent);
    return negative ? -v : v;
  }

  // The whole state as words, for sending to other ranks, and back.
  static constexpr int kWords = kLimbs + 1;
  std::array<std::int64_t, kWords> words() const {
    std::array<std::int64_t, kWords> w{};
    for (std::size_t j = 0; j < limbs_.size(); ++j) w[j] = limbs_[j];
    w[kLimbs] = special_;
    return w;
  }
  static ExactSum from_words(const std::int64_t* words) {
    ExactSum s;
    for (std::size_t j = 0; j < s.limbs_.size(); ++j) s.limbs_[j] = words[j];
    s.special_ = words[kLimbs];
    return s;
  }

 private:
  static constexpr int kAddsBetweenCarries = 1 << 30;
  static constexpr std::int64_t kNan = 1, kPlusInfinity = 2, kMinusInfinity = 4;

  // Every limb but the last into [0, 2^32), its excess (of either sign) carried upward.
  void carry() {
    for (std::size_t j = 0; j + 1 < limbs_.size(); ++j) {
      const std::int64_t c = limbs_[j] >> 32;  // floor division by 2^32
      limbs_[j] -= c * (std::int64_t{1} << 32);
      limbs_[j + 1] += c;
    }
    pending_ = 0;
  }
  // Two's complement of the whole number (carried, negative): each limb from 2^32 - 1 down.
  void negate() {
    for (auto& l : limbs_) l = -l;
    carry();
  }

  std::array<std::int64_t, kLimbs> limbs_{};
  std::int64_t special_ = 0;  // the non-finite values added (kNan, kPlusInfinity, kMinusInfinity)
  int pending_ = 0;
};

}  // namespace fountain
