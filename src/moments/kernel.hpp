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

#include <cstring>

namespace momentid {

// Four doubles in a vector register (a vector type of GCC and Clang: one AVX2 register, two SSE2
// ones without), read and written at any address. The kernels' sums keep the same lanes in both
// builds, so that they add alike.
using Four = double __attribute__((vector_size(4 * sizeof(double))));
[[gnu::always_inline]] inline Four load_four(const double* p) {
  Four v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
[[gnu::always_inline]] inline void store_four(double* p, Four v) { std::memcpy(p, &v, sizeof v); }

}  // namespace momentid
