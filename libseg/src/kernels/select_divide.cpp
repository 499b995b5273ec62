// Chooses the divide stage's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/divide.hpp"
#include "kernels/divide_levels.hpp"

namespace occseg::kernels {

void select_divide(DivideKernels& k, Isa cap) {
  k.count = scalar::count;
  k.nonzero_values = scalar::nonzero_values;
  k.total = scalar::total;
  k.sum_eight = scalar::sum_eight;
  k.add_counts = scalar::add_counts;
#ifdef __SSE2__
  if (cap >= Isa::sse2) {
    k.count = sse2::count;
    k.nonzero_values = sse2::nonzero_values;
  }
#endif
#if defined(__x86_64__) && defined(__GNUC__)
  // (Every AVX2 processor has the POPCNT the packing kernels use.)
  if (cap >= Isa::avx2 && cpu_has_avx2()) {
    k.count = avx2::count;
    k.nonzero_values = avx2::nonzero_values;
    k.total = avx2::total;
    k.sum_eight = avx2::sum_eight;
    k.add_counts = avx2::add_counts;
  }
  // The compress counting needs VBMI2 beyond the level's AVX-512 F, BW and VL; the listing of
  // non-zero counts goes with it.
  if (cap >= Isa::avx512 && cpu_has_avx512vbmi2()) {
    k.count = avx512::count;
    k.nonzero_values = avx512::nonzero_values;
  }
#endif
}

}  // namespace occseg::kernels
