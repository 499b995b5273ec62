// Chooses the labelling's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/label.hpp"
#include "kernels/label_levels.hpp"

namespace occseg::kernels {

void select_label(LabelKernels& k, Isa cap) {
  k.row_starts = scalar::label_row_starts;
  k.count_runs = scalar::label_count_runs;
  k.run_sum = scalar::label_run_sum;
#if defined(__SSE2__)
  if (cap >= Isa::sse2) {
    k.row_starts = sse2::label_row_starts;
    k.count_runs = sse2::label_count_runs;
    k.run_sum = sse2::label_run_sum;
  }
#endif
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx2 && cpu_has_avx2()) k.row_starts = avx2::label_row_starts;
  if (cap >= Isa::avx512 && cpu_has_avx512()) k.run_sum = avx512::label_run_sum;
#endif
}

}  // namespace occseg::kernels
