// The texture stage's kernels (kernels.hpp): the slots, and how a table fills them. Each slot is
// a loop over one row of voxels; stages/texture.cpp says what the two passes do with them.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"
#include "stages/quantise.hpp"
#include "util/aliasing.hpp"

namespace occseg::kernels {

using detail::code_t;

// A voxel whose parked step (quantise.hpp) a float kernel could not certify: the stage
// recomputes it in double (texture_unit()).
constexpr std::uint16_t kRecheckStep = 0xFFFF;
// count_steps adds to kStepHistograms interleaved histograms of kStepStride entries each (entry
// v: parked step v; entry 0, the flat voxels, is not used).
constexpr std::size_t kStepHistograms = 4;
constexpr std::size_t kStepStride = ContrastQuantizer::kFine + 1;

// `off` (every slot taking one): the offsets of the six neighbours in the order of texture.hpp's
// Neighbour (x-1, x+1, y-1, y+1, z-1, z+1); `present` masks the neighbours that exist (bit i for
// neighbour i; an absent one has offset 0). `p` points at the first voxel of the run.
struct TextureKernels {
  // ---- the map's values ----
  // True when every p[0, n) lies in [0, 1] (NaN excluded).
  bool (*values_in_range)(const float* p, std::size_t n) = nullptr;

  // ---- pass 1: parked steps, LBP codes, the distribution of the contrasts ----
  // The parked steps of n consecutive voxels with all six neighbours (or kRecheckStep where the
  // float arithmetic cannot certify one), into steps[0, n), and their LBP codes into lbp[0, n)
  // unless lbp is nullptr. maybe_recheck: false when no voxel got kRecheckStep (true says
  // nothing). Returns false when some centre p[0, n) lies outside [0, 1] (NaN included) and the
  // kernel checks values (checks_values); else true. A kernel that does not check values needs
  // every value it reads in [0, 1]; one that checks is defined for any float.
  bool (*contrast_row)(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* steps, std::uint8_t* lbp,
                       bool& maybe_recheck) = nullptr;
  bool checks_values = false;
  // contrast_row for any `present` (maps with an axis of size 1), never checking values, always
  // maybe_recheck. lbp may be nullptr.
  void (*contrast_row_any)(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present,
                           code_t* steps, std::uint8_t* lbp) = nullptr;
  // True when some steps[x] is kRecheckStep.
  bool (*any_recheck)(const code_t* steps, std::size_t n) = nullptr;
  // Adds the parked steps[0, n) to the histograms h (kStepHistograms x kStepStride); `list` is
  // room for n + 32 steps the kernel may use.
  void (*count_steps)(const code_t* steps, std::size_t n, std::uint64_t* h, std::uint16_t* list) = nullptr;

  // ---- pass 2: codes = lbp * bins + level of the parked step ----
  // (level of parked step v: (v != 0) + #{k < nr : v > rises[k]}, nr <= 16; steps <= kFine.)
  // In place: row[x] = lbp[x] * bins + level(row[x]) for x in [0, n).
  void (*codes_from_lbp)(code_t* row, const std::uint8_t* lbp, std::size_t n, const std::uint16_t* rises,
                         std::size_t nr, std::uint16_t bins) = nullptr;
  // The same with the LBP codes from the map (all six neighbours), for a prefix of the row:
  // returns how many voxels it did (0 where the level has no such kernel); the caller does the
  // rest with lbp_row, levels_row and combine_row.
  std::size_t (*codes_row)(const float* p, const std::ptrdiff_t* off, std::size_t n, const std::uint16_t* rises,
                           std::size_t nr, std::uint16_t bins, code_t* row) = nullptr;
  // The LBP codes of n consecutive voxels.
  void (*lbp_row)(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present,
                  std::uint8_t* out) = nullptr;
  // lvl[x] = level of parked step v[x].
  void (*levels_row)(const code_t* v, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                     std::uint16_t* lvl) = nullptr;
  // code[x] = lbp[x] * bins + lvl[x].
  void (*combine_row)(const std::uint8_t* lbp, const std::uint16_t* lvl, std::size_t n, std::uint16_t bins,
                      code_t* code) = nullptr;
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_texture(TextureKernels& k, Isa cap);

}  // namespace occseg::kernels
