// The refinement's kernels in plain C++ (kernels/refine.hpp): the meaning of every slot.
#include "kernels/generic/refine_loops.hpp"

namespace occseg::kernels::scalar {

bool any_boundary(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  return generic::any_boundary(a, b, n);
}

bool any_occupied(const std::uint8_t* s, std::size_t n) { return generic::any_occupied(s, n); }

std::size_t next_boundary(const std::uint8_t* st, std::size_t k, std::size_t len, int step) {
  return generic::next_boundary_from(st, k, len, step);
}

std::size_t window_starts(const std::uint8_t* prev, const std::uint8_t* cur, std::uint8_t* skip, std::size_t nx,
                          std::uint32_t* lanes) {
  return generic::window_starts_from(prev, cur, skip, 0, nx, lanes, 0);
}

PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur, std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                   std::size_t nx, const word_t* const* occ, const word_t* const* unk) {
  PlaneRow r;
  generic::lane_windows(prev, cur, rs, rows, skip, 0, nx, occ, unk, generic::PlainStarts{prev, cur, skip}, r);
  return r;
}

void pack_states(const std::uint8_t* st, std::size_t nx, word_t* unknown, word_t* free) {
  generic::clear_words(unknown, nx);
  generic::clear_words(free, nx);
  generic::pack_states_from(st, 0, nx, unknown, free);
}

void unpack_unknown(const word_t* w, std::size_t nx, std::uint8_t* st) { generic::unpack_unknown_from(w, 0, nx, st); }

void write_cells_row(const std::uint8_t* cs, const word_t* w, std::size_t nx, std::uint8_t* st) {
  generic::write_cells_row_from(cs, w, 0, nx, st);
}

}  // namespace occseg::kernels::scalar
