// Chooses the texture stage's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/texture.hpp"
#include "kernels/texture_impl.hpp"

namespace occseg::kernels {

void select_texture(TextureKernels& k, Isa cap) {
  // scalar and sse2: the compiler's code for the baseline (no SSE2 kernel of its own)
  k.values_in_range = scalar::values_in_range;
  k.contrast_row = scalar::contrast_row;
  k.checks_values = false;
  k.contrast_row_any = scalar::contrast_row_any;
  k.any_recheck = scalar::any_recheck;
  k.count_steps = scalar::count_steps;
  k.codes_from_lbp = scalar::codes_from_lbp;
  k.codes_row = scalar::codes_row;
  k.lbp_row = scalar::lbp_row;
  k.levels_row = scalar::levels_row;
  k.combine_row = scalar::combine_row;
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx2 && cpu_has_avx2()) {
    k.values_in_range = avx2::values_in_range;
    k.contrast_row = avx2::contrast_row;
    k.checks_values = true;
    k.any_recheck = avx2::any_recheck;
    k.count_steps = avx2::count_steps;
    k.codes_from_lbp = avx2::codes_from_lbp;
    k.codes_row = avx2::codes_row;
    k.lbp_row = avx2::lbp_row;
    k.levels_row = avx2::levels_row;
    k.combine_row = avx2::combine_row;
  }
  if (cap >= Isa::avx512 && cpu_has_avx512()) {
    k.contrast_row = avx512::contrast_row;
    k.codes_from_lbp = avx512::codes_from_lbp;
    // The compress of 16-bit lanes (VBMI2) from this level on, where the processor has it.
    if (cpu_has_avx512vbmi2()) k.count_steps = avx512::count_steps;
  }
  if (cap >= Isa::avx512vbmi && cpu_has_avx512vbmi()) k.contrast_row = avx512::contrast_row_vbmi;
#else
  (void)cap;
#endif
}

}  // namespace occseg::kernels
