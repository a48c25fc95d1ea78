// A particle's time bin: its step is 2^bin integer time units.
#pragma once
#include <cstdint>

namespace fountain {

using TimeBin = std::int8_t;
inline constexpr TimeBin kNoBin = 127;  // no limit, no request

}  // namespace fountain
