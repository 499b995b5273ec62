// The label array as the stages' scratch: the one owner of a call's per-voxel memory, carving
// the array into typed views at offsets written down once, here.
#pragma once
#include <cstddef>
#include <cstdint>

#include "occseg/uninit_vector.hpp"
#include "util/aliasing.hpp"

namespace occseg::detail {

// Until the labelling writes the labels, the n labels' 4n bytes hold, in turn:
//   [0, 2n)   the texture codes (uint16), from the fused map pass through the division;
//   [2n, 3n)  the texture operator's scratch (its LBP codes) while it runs;
//   [0, 3n)   the refinement's bit masks, once the division has counted the codes;
//   [3n, 4n)  the own states: as bits (own_bits) from the fused map pass through the rules, or
//             as bytes (own_bytes) when a plugin's texture leaves them to the creation.
// One array allocated (or recycled) and paged in once instead of four: fewer allocations,
// zero-fills and page faults, and a peak of the labels and the states only.
class LabelScratch {
 public:
  // `labels` holds at least `voxels` elements (resized by the caller).
  LabelScratch(LabelArray& labels, std::size_t voxels)
      : bytes_(reinterpret_cast<std::uint8_t*>(labels.data())), n_(voxels) {}

  code_t* codes() const { return reinterpret_cast<code_t*>(bytes_); }
  std::uint8_t* texture_scratch() const { return bytes_ + 2 * n_; }
  std::uint8_t* refinement() const { return bytes_; }
  std::size_t refinement_bytes() const { return 3 * n_; }
  std::uint8_t* own_bytes() const { return bytes_ + 3 * n_; }
  // Room for the two own-state masks of `words` words each from the first cache line at or past
  // 3n (the array starts on a page), or nullptr when they do not fit there (maps a few voxels
  // wide: a word per row of voxels).
  word_t* own_bits(std::size_t words) const {
    const std::size_t at = (3 * n_ + 63) / 64 * 64;
    return at + 2 * words * sizeof(word_t) <= 4 * n_ ? reinterpret_cast<word_t*>(bytes_ + at) : nullptr;
  }

 private:
  std::uint8_t* bytes_;
  std::size_t n_;
};

}  // namespace occseg::detail
