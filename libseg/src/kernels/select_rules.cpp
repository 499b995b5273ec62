// Chooses the default rules' kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/rules.hpp"

namespace occseg::kernels {

void select_rules(RulesKernels& k, Isa cap) {
  k.rules_row = scalar::rules_row;
  k.unpack_half = scalar::unpack_half;
#if defined(__SSE2__)
  if (cap >= Isa::sse2) k.unpack_half = sse2::unpack_half;
#endif
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx2 && cpu_has_avx2()) k.rules_row = avx2::rules_row;
  if (cap >= Isa::avx512 && cpu_has_avx512()) k.rules_row = avx512::rules_row;
#endif
}

}  // namespace occseg::kernels
