// The contrast quantisation of the texture (section 2.2): contrast values to levels of equal
// frequency, the one definition the built-in operator, the plugin host and the kernels use.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occseg {

// Maps a contrast value to one of `bins` levels. Level 0 holds exactly C = 0 (flat or one-sided
// units); levels 1..bins-1 split the non-zero contrasts of the whole map into classes of equal
// frequency (Ojala and Pietikainen), measured on a grid of kFine steps so that equal values share
// a level.
//
// The texture's first pass parks each voxel's "parked step": fine_step(C) + 1 for C > 0, 0 for
// C = 0 (parked_step()); the levels are then looked up from it (parked_levels(), rises()).
class ContrastQuantizer {
 public:
  static constexpr int kFine = 4096;
  ContrastQuantizer() = default;
  // Builds the cut values from a histogram of the fine steps of the non-zero contrasts
  // (kFine entries). Throws Error(invalid_argument) for bins outside [2, 64].
  ContrastQuantizer(int bins, const std::vector<std::uint64_t>& fine_histogram);
  int bins() const { return bins_; }
  // The fine step of a contrast: floor(c * kFine), clamped into [0, kFine).
  static int fine_step(double c) {
    int f = static_cast<int>(c * kFine);
    return f < 0 ? 0 : (f >= kFine ? kFine - 1 : f);
  }
  // The parked step of a contrast: fine_step(c) + 1 for c > 0, 0 for c <= 0.
  static std::uint16_t parked_step(double c) { return c > 0 ? static_cast<std::uint16_t>(fine_step(c) + 1) : 0; }
  int level(double c) const { return c <= 0 ? 0 : lut_[fine_step(c)]; }
  // The level of a non-zero contrast whose fine step is `step` (0..kFine-1): level(c) for c > 0
  // is level_of_step(fine_step(c)).
  int level_of_step(int step) const { return lut_[step]; }
  // Entry v (0..kFine) is the level of parked step v.
  std::vector<std::uint16_t> parked_levels() const;
  // The parked steps after which the level rises, in order, each as often as the level rises
  // there (tied cuts make it jump): the level of parked step v is
  // (v != 0) + #{r in rises() : v > r}, a few compares instead of a table for few levels.
  std::vector<std::uint16_t> rises() const;

 private:
  int bins_ = 0;
  std::vector<std::uint8_t> lut_;  // fine step -> level 1..bins-1
};

// The levels of `count` contrasts quantised over their own distribution as the built-in
// operator quantises its map's (the plugin host's contrast_levels): `none` for a NaN contrast (no
// texture), else ContrastQuantizer(bins, ...).level(c). Throws Error(invalid_argument) for bins
// outside [2, 64].
void quantise_contrasts(const double* contrast, std::size_t count, int bins, std::uint16_t* levels,
                        std::uint16_t none);

}  // namespace occseg
