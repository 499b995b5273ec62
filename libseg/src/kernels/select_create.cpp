// Chooses the create stage's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/create.hpp"
#include "kernels/create_impl.hpp"

namespace occseg::kernels {

void select_create(CreateKernels& k, Isa cap) {
  k.add_cells = scalar::add_cells;
  k.own_states = scalar::own_states;
  k.own_bits = scalar::own_bits;
  k.pack_equal = scalar::pack_equal;
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::sse2) {
    k.own_states = sse2::own_states;
    k.pack_equal = sse2::pack_equal;  // (also above: no wider kernel of its own)
  }
  if (cap >= Isa::avx2 && cpu_has_avx2()) {
    k.add_cells = avx2::add_cells;
    k.own_states = avx2::own_states;
    k.own_bits = avx2::own_bits;
  }
  if (cap >= Isa::avx512 && cpu_has_avx512()) {
    k.add_cells = avx512::add_cells;
    k.own_bits = avx512::own_bits;
  }
#else
  (void)cap;
#endif
}

}  // namespace occseg::kernels
