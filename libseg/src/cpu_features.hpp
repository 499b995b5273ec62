// Run-time processor features (internal): the library is built for generic x86-64 and picks its
// hand-written AVX2 kernels only where the processor has AVX2.
#pragma once

namespace occseg {

// True when the processor running this has AVX2 (asked once).
inline bool cpu_has_avx2() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
#else
  return false;
#endif
}

}  // namespace occseg
