// Run-time processor features (internal): the library is built for generic x86-64 and picks its
// hand-written AVX2 (and AVX-512) kernels only where the processor has them.
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

// True when the processor (and the system, which must save the registers) has AVX-512 F, BW and
// VL (every AVX-512 processor since 2017). Under valgrind, which has no AVX-512, this is false:
// the AVX2 kernels run there.
inline bool cpu_has_avx512() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool yes = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                          __builtin_cpu_supports("avx512vl");
  return yes;
#else
  return false;
#endif
}

// AVX-512 VBMI (permutes of bytes) besides AVX-512F, BW and VL.
inline bool cpu_has_avx512vbmi() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool yes = cpu_has_avx512() && __builtin_cpu_supports("avx512vbmi");
  return yes;
#else
  return false;
#endif
}

// AVX-512 VBMI2 (compress of 16-bit lanes) besides AVX-512F and BW.
inline bool cpu_has_avx512vbmi2() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool yes = cpu_has_avx512() && __builtin_cpu_supports("avx512vbmi2");
  return yes;
#else
  return false;
#endif
}

}  // namespace occseg
