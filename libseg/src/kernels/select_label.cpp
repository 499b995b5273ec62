// Chooses the labelling's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/label.hpp"
#include "kernels/label_levels.hpp"

namespace occseg::kernels {

void select_label(LabelKernels& k, Isa cap) {
  k.find_state = scalar::label_find_state;
  k.find_other = scalar::label_find_other;
  k.run_start = scalar::label_run_start;
  k.count_runs = scalar::label_count_runs;
  k.run_sum = scalar::label_run_sum;
#if defined(__SSE2__)
  if (cap >= Isa::sse2) {
    k.find_state = sse2::label_find_state;
    k.find_other = sse2::label_find_other;
    k.run_start = sse2::label_run_start;
    k.count_runs = sse2::label_count_runs;
    k.run_sum = sse2::label_run_sum;
  }
#endif
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx512 && cpu_has_avx512()) k.run_sum = avx512::label_run_sum;
#endif
}

}  // namespace occseg::kernels
