// The contrast quantisation of the texture (quantise.hpp).
#include "stages/quantise.hpp"

#include <cmath>

#include "occseg/error.hpp"

namespace occseg {

ContrastQuantizer::ContrastQuantizer(int bins, const std::vector<std::uint64_t>& fine)
    : bins_(bins), lut_(kFine, 1) {
  if (bins < 2 || bins > 64 || fine.size() != static_cast<std::size_t>(kFine))
    throw Error(Status::invalid_argument, "contrast_bins must be in [2, 64]");
  std::uint64_t total = 0;
  for (auto c : fine) total += c;
  const int levels = bins - 1;  // non-zero contrast levels
  if (total == 0 || levels == 1) return;
  // cut[k] = first fine step whose cumulative count reaches k/levels of the total; a step belongs
  // to level 1 + #{k : cut[k] < step}, so ties (equal contrasts) always share one level.
  std::vector<int> cut;
  std::uint64_t cum = 0;
  int k = 1;
  for (int f = 0; f < kFine && k < levels; ++f) {
    cum += fine[f];
    while (k < levels && cum * levels >= total * static_cast<std::uint64_t>(k)) {
      cut.push_back(f);
      ++k;
    }
  }
  for (int f = 0; f < kFine; ++f) {
    int lvl = 1;
    for (int c : cut) lvl += (c < f);
    lut_[f] = static_cast<std::uint8_t>(lvl);
  }
}

std::vector<std::uint16_t> ContrastQuantizer::parked_levels() const {
  std::vector<std::uint16_t> level(kFine + 1, 0);
  for (int f = 0; f < kFine; ++f) level[f + 1] = static_cast<std::uint16_t>(level_of_step(f));
  return level;
}

std::vector<std::uint16_t> ContrastQuantizer::rises() const {
  const std::vector<std::uint16_t> level = parked_levels();
  std::vector<std::uint16_t> r;
  for (int v = 2; v <= kFine; ++v)
    for (int k = level[v - 1]; k < level[v]; ++k) r.push_back(static_cast<std::uint16_t>(v - 1));
  return r;
}

void quantise_contrasts(const double* contrast, std::size_t count, int bins, std::uint16_t* levels,
                        std::uint16_t none) {
  std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
  for (std::size_t i = 0; i < count; ++i)
    if (contrast[i] > 0) ++fine[ContrastQuantizer::fine_step(contrast[i])];
  const ContrastQuantizer q(bins, fine);
  for (std::size_t i = 0; i < count; ++i)
    levels[i] = std::isnan(contrast[i]) ? none : static_cast<std::uint16_t>(q.level(contrast[i]));
}

}  // namespace occseg
