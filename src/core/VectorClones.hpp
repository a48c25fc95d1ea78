// FOUNTAIN_VECTOR_CLONES: compile a hot loop for AVX2 (or AVX-512) and for any x86-64, picked at load time.
#pragma once

// The release build targets plain x86-64 (SSE2) so its binaries run anywhere; loops written
// over independent lanes gain ~1.3x from AVX2's wider vectors. AVX2 does not imply FMA, so
// the clones round every operation alike and give the same bits on any machine.
// FOUNTAIN_WIDE_VECTOR_CLONES adds an AVX-512 clone, for loops of sixteen float lanes (AVX2
// runs them as two registers). AVX-512F does have FMA, so a file using it must be compiled
// with -ffp-contract=off (src/CMakeLists.txt) to keep the clones' bits alike.
#if defined(__x86_64__) && !defined(__AVX2__)
#define FOUNTAIN_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#define FOUNTAIN_WIDE_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define FOUNTAIN_VECTOR_CLONES
#define FOUNTAIN_WIDE_VECTOR_CLONES
#endif
