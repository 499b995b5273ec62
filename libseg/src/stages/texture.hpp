// Stage 1 of the paper (section 2.2): the 6-neighbour LBP/C texture unit of every voxel.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/texture_codes.hpp"

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

// Maps a contrast value to one of `bins` levels. Level 0 holds exactly C = 0 (flat or one-sided
// units); levels 1..bins-1 split the non-zero contrasts of the whole map into classes of equal
// frequency (Ojala and Pietikainen), measured on a 4096-step grid so equal values share a level.
class ContrastQuantizer {
 public:
  static constexpr int kFine = 4096;
  ContrastQuantizer() = default;
  // Builds cut values from a histogram of fine steps of the non-zero contrasts.
  ContrastQuantizer(int bins, const std::vector<std::uint64_t>& fine_histogram);
  int bins() const { return bins_; }
  static int fine_step(double c) {
    int f = static_cast<int>(c * kFine);
    return f < 0 ? 0 : (f >= kFine ? kFine - 1 : f);
  }
  int level(double c) const { return c <= 0 ? 0 : lut_[fine_step(c)]; }
  // The level of a non-zero contrast whose fine step is `step` (0..kFine-1): level(c) for c > 0
  // is level_of_step(fine_step(c)).
  int level_of_step(int step) const { return lut_[step]; }

 private:
  int bins_ = 0;
  std::vector<std::uint8_t> lut_;  // fine step -> level 1..bins-1
};

// Computes the texture code of every voxel: a first pass collects the contrast distribution for
// the quantiser, a second writes the codes. Deterministic for any thread count. Throws
// Error(bad_value) naming the first voxel (as check_probabilities() does) when a value is NaN,
// infinite or outside [0, 1]; the first pass tests every row as it reads it.
TextureMap compute_texture(const Grid& grid, int contrast_bins, int threads);

namespace detail {
// The contrast kernels of the texture's first pass, slowest first. All give identical codes.
// avx512vbmi is the AVX-512 kernel with its count of neighbours looked up by a byte permute
// (AVX-512 VBMI), where the processor has it.
enum class TextureKernel { compiler = 0, avx2 = 1, avx512 = 2, avx512vbmi = 3, fastest = 3 };
// For tests and benchmarks: compute_texture uses the fastest kernel up to `k` that the processor
// has (the compiler-vectorised one always; the hand-written AVX2 and AVX-512 ones where the
// processor has them), and so do the creation's cell sums (which segment() has the texture's
// first pass add). Process-wide; `fastest` by default.
void set_texture_kernel(TextureKernel k);
TextureKernel texture_kernel();  // the setting
}  // namespace detail

}  // namespace occseg
