// Stage 1 of the paper (section 2.2): the 6-neighbour LBP/C texture unit of every voxel.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/texture_codes.hpp"
#include "stages/quantise.hpp"

namespace occseg {

// Neighbour order and binomial weights of the LBP code (bit i has weight 2^i):
//   bit 0 (1): x-1   bit 1 (2): x+1   bit 2 (4): y-1   bit 3 (8): y+1   bit 4 (16): z-1   bit 5 (32): z+1
enum Neighbour { kXMinus = 0, kXPlus, kYMinus, kYPlus, kZMinus, kZPlus };

struct TextureUnit {
  std::uint8_t lbp = 0;   // 0..63
  double contrast = 0;    // mean(neighbours with bit 1) - mean(neighbours with bit 0); 0 if one side is empty
};

// The texture unit of one voxel. `present` masks neighbours that exist (bit i as above); absent
// neighbours (along an axis of size 1) get bit 0 and take no part in the contrast.
TextureUnit texture_unit(double centre, const double neighbours[6], unsigned present = 0x3F);

// Computes the texture code of every voxel, lbp * contrast_bins + the level of its contrast
// (ContrastQuantizer, quantise.hpp): a first pass collects the contrast distribution for the
// quantiser, a second writes the codes. Deterministic for any thread count and kernels. Throws
// Error(bad_value) naming the first voxel (as check_probabilities() does) when a value is NaN,
// infinite or outside [0, 1]; the first pass tests every row as it reads it.
TextureMap compute_texture(const Grid& grid, int contrast_bins, int threads,
                           const kernels::Table& k = kernels::active());

}  // namespace occseg
