// The divide stage's kernels (kernels.hpp): the slots, and how a table fills them.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"
#include "occseg/grid.hpp"
#include "occseg/result.hpp"

namespace occseg::kernels {

// A texture code as the kernels read it. May alias any type: segment() keeps the codes in the
// storage of its label array (stages/codes.hpp's detail::code_t, which converts to this).
typedef std::uint16_t __attribute__((__may_alias__)) code_t;

// The codes of one block and what a counting kernel may assume of them.
struct BlockCodes {
  const code_t* codes;  // the whole map's, x fastest
  Dims dims;            // the map's
  Block b;              // inside the map
  // False: no voxel of b holds kNoTexture, so none is tested. True: kNoTexture voxels are skipped.
  bool may_lack_texture;
  // Hints, never needed for the right counts: the code most of b's voxels are expected to hold,
  // and the next most frequent one, or second == common for no guess.
  code_t common, second;
};

struct DivideKernels {
  // h[c] = number of voxels of in.b with code c, for c < bins (h: `bins` counts, overwritten);
  // kNoTexture voxels are not counted. Every code of b is below bins or kNoTexture.
  void (*count)(const BlockCodes& in, std::size_t bins, std::uint32_t* h) = nullptr;

  // The non-zero values of a[i] (b: of a[i] + b[i]; b may be null) for i < n, in order of i, into
  // out, which has room for n + 16 values (the vector kernels store whole vectors); returns how
  // many. Sums of counts of one block: they never wrap.
  std::size_t (*nonzero_values)(const std::uint32_t* a, const std::uint32_t* b, std::size_t n,
                                std::uint32_t* out) = nullptr;

  // h[0] + ... + h[n - 1].
  std::uint64_t (*total)(const std::uint32_t* h, std::size_t n) = nullptr;

  // h[i] = a[i] + a[stride + i] + ... + a[7 * stride + i] for i < n: eight octants' histograms,
  // `stride` apart, summed into their parent's (h does not overlap them).
  void (*sum_eight)(std::uint32_t* h, const std::uint32_t* a, std::size_t stride, std::size_t n) = nullptr;

  // h[i] += a[i] for i < n (h and a do not overlap).
  void (*add_counts)(std::uint32_t* h, const std::uint32_t* a, std::size_t n) = nullptr;
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_divide(DivideKernels& k, Isa cap);

}  // namespace occseg::kernels
