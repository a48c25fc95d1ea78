// FOUNTAIN_VECTOR_CLONES: compile a hot loop for AVX2 and for any x86-64, picked at load time.
#pragma once

// The release build targets plain x86-64 (SSE2) so its binaries run anywhere; loops written
// over independent lanes gain ~1.3x from AVX2's wider vectors. AVX2 does not imply FMA, so
// the clones round every operation alike and give the same bits on any machine.
#if defined(__x86_64__) && !defined(__AVX2__)
#define FOUNTAIN_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FOUNTAIN_VECTOR_CLONES
#endif
