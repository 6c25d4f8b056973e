#pragma once
// MOMENTID_KERNEL marks the pass's kernels (the moments', the channel sums', the time steps'
// check) that are also built for AVX2, chosen when the program loads on a processor that has it.
// Without fused multiply-adds (-ffp-contract=off) both builds compute the same numbers. (GCC only:
// clang refuses clones of functions declared before, as these are, in the class; and not under
// ThreadSanitizer, MOMENTID_TARGET_CLONES=OFF, whose runtime is not ready when the loader chooses.)

#if defined(__x86_64__) && defined(__gnu_linux__) && !defined(__clang__) && \
    !defined(MOMENTID_NO_TARGET_CLONES)
#define MOMENTID_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define MOMENTID_KERNEL
#endif
