// A parallel loop handed to code below the engine, so that it need not know the executor.
#pragma once
#include <cstddef>
#include <functional>

namespace fountain {

// Calls fn(k) for k in [0, n), in any order and possibly in parallel; an empty ForEach
// means the caller's serial loop.
using ForEach = std::function<void(std::size_t n, const std::function<void(std::size_t)>& fn)>;

// Calls fn(k) for every k in [0, n) through for_each when there is one, serially otherwise.
inline void for_each_or_serial(const ForEach& for_each, std::size_t n, const std::function<void(std::size_t)>& fn) {
  if (for_each) {
    for_each(n, fn);
  } else {
    for (std::size_t k = 0; k < n; ++k) fn(k);
  }
}

}  // namespace fountain
