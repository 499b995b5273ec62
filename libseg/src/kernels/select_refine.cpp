// Chooses the refinement's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/create_impl.hpp"  // pack_equal: one kernel for both stages
#include "kernels/refine.hpp"

namespace occseg::kernels {

void select_refine(RefineKernels& k, Isa cap) {
  k.any_boundary = scalar::any_boundary;
  k.any_occupied = scalar::any_occupied;
  k.next_boundary = scalar::next_boundary;
  k.window_starts = scalar::window_starts;
  k.plane_row = scalar::plane_row;
  k.pack_states = scalar::pack_states;
  k.pack_equal = scalar::pack_equal;
  k.unpack_unknown = scalar::unpack_unknown;
  k.write_cells_row = scalar::write_cells_row;
#if defined(__SSE2__)
  if (cap >= Isa::sse2) {
    k.next_boundary = sse2::next_boundary;
    k.window_starts = sse2::window_starts;
    k.plane_row = sse2::plane_row;
    k.pack_states = sse2::pack_states;
    k.pack_equal = sse2::pack_equal;
    k.unpack_unknown = sse2::unpack_unknown;
  }
#endif
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx2 && cpu_has_avx2()) {
    k.any_boundary = avx2::any_boundary;
    k.any_occupied = avx2::any_occupied;
    k.pack_states = avx2::pack_states;
    k.write_cells_row = avx2::write_cells_row;
    k.plane_row = avx2::plane_row;
  }
  if (cap >= Isa::avx512 && cpu_has_avx512()) k.plane_row = avx512::plane_row;
#endif
}

}  // namespace occseg::kernels
