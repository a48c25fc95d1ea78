// Whether the processor running the code has the vector instructions a hand-written loop needs.
#pragma once

namespace fountain {

// AVX-512 F and VL (compress stores into registers, masks): asked of the processor once.
inline bool cpu_has_avx512() {
#if defined(__x86_64__) && defined(__GNUC__)
  // Dynamic initialisation may run before the library's own CPU detection: ask for it first.
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  }();
  return has;
#else
  return false;
#endif
}

}  // namespace fountain
