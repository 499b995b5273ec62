// The labelling's AVX-512 kernel: a run's eight sum lanes in one register.
#include "kernels/label_levels.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

namespace occseg::kernels::avx512 {

#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning inside its own AVX-512 intrinsics; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// One conversion and one addition per eight voxels, the same additions in the same order as the
// scalar lanes.
__attribute__((target("avx512f"))) double label_run_sum(const float* v, std::size_t n) {
  __m512d acc = _mm512_setzero_pd();
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) acc = _mm512_add_pd(acc, _mm512_cvtps_pd(_mm256_loadu_ps(v + k)));
  double l[8];
  _mm512_storeu_pd(l, acc);
  for (; k < n; ++k) l[k & 7] += v[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}
#pragma GCC diagnostic pop

}  // namespace occseg::kernels::avx512

#endif
