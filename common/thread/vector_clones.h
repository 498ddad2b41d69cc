#pragma once
// MICRODEX_VECTOR_CLONES before a function with an element-wise loop builds it for AVX-512 and
// AVX2 besides the baseline, chosen at load by the CPU (GCC's target_clones). Only for loops
// whose elements are independent: each element is then the same multiplies and adds in every
// build (the project compiles with -ffp-contract=off, so no build fuses them), so every
// machine computes the same bits and only the vector width differs. Reductions (dot
// products) would change their order with the width: not for them.

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__)
#define MICRODEX_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define MICRODEX_VECTOR_CLONES
#endif
