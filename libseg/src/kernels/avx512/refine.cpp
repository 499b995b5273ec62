// The refinement's kernels in AVX-512 (kernels/refine.hpp): a plane scan's row 64 lanes at a time,
// every window of them at once. A block of 64 lanes is one word of the own states' bit rows, so
// each window row's occupied and unknown bits of the block are one word each; the four cases
// (window_moves) are then a few operations on 64-lane masks.
#include "kernels/generic/refine_loops.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

namespace occseg::kernels::avx512 {

using generic::kFree;
using generic::kFreeXorOccupied;

__attribute__((target("avx512f,avx512bw"))) PlaneRow plane_row(const std::uint8_t* prev, std::uint8_t* cur,
                                                                std::ptrdiff_t rs, int rows, std::uint8_t* skip,
                                                                std::size_t nx, const word_t* const* occ,
                                                                const word_t* const* unk) {
  const __m512i boundary = _mm512_set1_epi8(kFreeXorOccupied), free = _mm512_set1_epi8(kFree);
  const __m512i zero = _mm512_setzero_si512(), one = _mm512_set1_epi8(1);
  PlaneRow r;
  for (std::size_t x = 0; x < nx; x += 64) {
    const __mmask64 lanes = nx - x >= 64 ? ~__mmask64{0} : (__mmask64{1} << (nx - x)) - 1;
    const __m512i p = _mm512_maskz_loadu_epi8(lanes, prev + x), c = _mm512_maskz_loadu_epi8(lanes, cur + x);
    const __m512i sk = _mm512_maskz_loadu_epi8(lanes, skip + x);
    const __mmask64 start = _mm512_mask_cmpeq_epi8_mask(lanes, _mm512_xor_si512(p, c), boundary) &
                            _mm512_cmpeq_epi8_mask(sk, zero);
    __m512i next = _mm512_subs_epu8(sk, one);  // every other lane counts down
    if (start) {
      r.started = true;
      const std::size_t i = x / 64;
      const __mmask64 from_free = start & _mm512_cmpeq_epi8_mask(p, free), from_occupied = start & ~from_free;
      // Window row w holds the lanes whose voxels 0..w all equal the boundary voxel; per lane, its
      // own states on `from`'s side and on the entered segment's side.
      __mmask64 in[64], into_side[64];
      __mmask64 any_from = 0, any_into = 0, held = start;
      __m512i length = zero;  // the window's voxels less one
      int w = 0;
      for (; w < rows && held; ++w) {
        if (w > 0) {
          held &= _mm512_mask_cmpeq_epi8_mask(held, _mm512_maskz_loadu_epi8(held, cur + w * rs + x), c);
          if (!held) break;
          length = _mm512_mask_add_epi8(length, held, length, one);
        }
        const std::uint64_t o = occ[w][i], u = unk[w][i] & ~o, f = ~o & ~u;
        in[w] = held;
        into_side[w] = (from_free & o) | (from_occupied & f);
        any_from |= held & ((from_free & f) | (from_occupied & o));
        any_into |= held & into_side[w];
      }
      for (int k = 0; k < w; ++k) {
        const __mmask64 moves = in[k] & any_from & ~(any_into & into_side[k]);
        if (!moves) continue;
        _mm512_mask_storeu_epi8(cur + k * rs + x, moves, p);
        if (moves & from_occupied) r.occupied_rows |= std::uint64_t{1} << k;
      }
      next = _mm512_mask_blend_epi8(start, next, length);
    }
    _mm512_mask_storeu_epi8(skip + x, lanes, next);
  }
  return r;
}

}  // namespace occseg::kernels::avx512
#endif
