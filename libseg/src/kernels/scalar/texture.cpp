// The texture kernels in plain C++ (kernels/texture.hpp): the meaning of every texture kernel,
// compiled for the baseline instruction set.
#include "kernels/generic/texture_loops.hpp"
#include "kernels/texture_impl.hpp"

namespace occseg::kernels::scalar {

namespace {

// generic::contrast_row and generic::lbp_row for the neighbourhood `present`, instantiated for
// each (rows of maps with an axis of size 1 are few: no vector kernels for them).
template <unsigned P>
void contrast_any(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* out, unsigned present) {
  if constexpr (P == 64) {
    (void)p, (void)off, (void)n, (void)out, (void)present;
  } else if (present == P) {
    generic::contrast_row<P>(p, off, n, out);
  } else {
    contrast_any<P + 1>(p, off, n, out, present);
  }
}
template <unsigned P>
void lbp_any(const float* p, const std::ptrdiff_t* off, std::size_t n, std::uint8_t* out, unsigned present) {
  if constexpr (P == 64) {
    (void)p, (void)off, (void)n, (void)out, (void)present;
  } else if (present == P) {
    generic::lbp_row<P>(p, off, n, out);
  } else {
    lbp_any<P + 1>(p, off, n, out, present);
  }
}

}  // namespace

bool contrast_row(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* steps, std::uint8_t* lbp,
                  bool& maybe_recheck) {
  generic::contrast_row<63>(p, off, n, steps);
  if (lbp) generic::lbp_row<63>(p, off, n, lbp);
  maybe_recheck = true;
  return true;  // (values not checked)
}

void contrast_row_any(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present, code_t* steps,
                      std::uint8_t* lbp) {
  contrast_any<0>(p, off, n, steps, present);
  if (lbp) lbp_any<0>(p, off, n, lbp, present);
}

bool values_in_range(const float* p, std::size_t n) { return generic::values_in_range(p, n); }

bool any_recheck(const code_t* steps, std::size_t n) { return generic::any_recheck(steps, n); }

// Four voxels whose steps are all 0 (flat regions: most of a map) are skipped with one test;
// otherwise each goes to its own histogram, so runs of equal steps do not chain their increments
// through one counter.
void count_steps(const code_t* v, std::size_t n, std::uint64_t* h, std::uint16_t*) {
  std::size_t x = 0;
  for (; x + 4 <= n; x += 4) {
    std::uint64_t four;
    std::memcpy(&four, v + x, 8);
    if (four == 0) continue;
    ++h[v[x]];
    ++h[kStepStride + v[x + 1]];
    ++h[2 * kStepStride + v[x + 2]];
    ++h[3 * kStepStride + v[x + 3]];
  }
  for (; x < n; ++x) ++h[v[x]];
}

void codes_from_lbp(code_t* row, const std::uint8_t* lbp, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                    std::uint16_t bins) {
  constexpr std::size_t kChunk = 256;  // levels first, then codes: two loops that vectorise
  std::uint16_t lvl[kChunk];
  for (std::size_t x = 0; x < n; x += kChunk) {
    const std::size_t m = std::min(kChunk, n - x);
    generic::levels_row(row + x, m, rises, nr, lvl);
    generic::combine_row(lbp + x, lvl, m, bins, row + x);
  }
}

std::size_t codes_row(const float*, const std::ptrdiff_t*, std::size_t, const std::uint16_t*, std::size_t,
                      std::uint16_t, code_t*) {
  return 0;  // (no fused kernel: the caller takes the LBP codes and the levels apart)
}

void lbp_row(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present, std::uint8_t* out) {
  if (present == 63) generic::lbp_row<63>(p, off, n, out);
  else lbp_any<0>(p, off, n, out, present);
}

void levels_row(const code_t* v, std::size_t n, const std::uint16_t* rises, std::size_t nr, std::uint16_t* lvl) {
  generic::levels_row(v, n, rises, nr, lvl);
}

void combine_row(const std::uint8_t* lbp, const std::uint16_t* lvl, std::size_t n, std::uint16_t bins, code_t* code) {
  generic::combine_row(lbp, lvl, n, bins, code);
}

}  // namespace occseg::kernels::scalar
