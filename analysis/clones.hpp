// RIG_CLONES: the hot kernels are compiled for AVX-512, AVX2 and baseline (target_clones) and
// picked at load time by an ifunc resolver. ThreadSanitizer cannot run a program whose ifunc
// resolvers run before its runtime is set up, so a TSan build (RIG_TSAN) compiles them for
// baseline only: the same code, one target. So does clang (the fuzz harnesses and the sanitizer
// pass): clang 14 emitted one AVX-512 body with no resolver, which stopped with SIGILL on a CPU
// without AVX-512 (2026-11-25).
#pragma once

#if defined(RIG_NO_CLONES) || defined(__clang__)
#define RIG_CLONES
#else
#define RIG_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#endif
