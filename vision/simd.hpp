#pragma once
// Hot loops are written as plain scalar loops the compiler vectorises; ALIGHT_MULTIVERSION
// compiles them also for AVX2 and picks the variant at load time (GCC function multi-versioning),
// so the binary still runs on the paper's Atom (SSE only) but uses the wide units where present.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define ALIGHT_MULTIVERSION __attribute__((target_clones("avx2", "default")))
#else
#define ALIGHT_MULTIVERSION
#endif
