// Stage 3 (section 3.1): hierarchical division of the map into blocks of uniform texture.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"
#include "stages/texture.hpp"

namespace occseg {

// The split decision of eq. (2) over the n sibling histograms of a block: split when
// R = Gmax / Gmin > X over all their pairs, g(a, b) (a < b) giving a pair's statistic, never
// negative. Gmin = 0 with Gmax > 0 is an infinite ratio (split); all G = 0 means identical
// textures (no split); fewer than two histograms give no evidence (no split). Pairs come in the
// order (0,1), (0,2), (1,2), (0,3), ... and, unless every_pair, stop as soon as the pairs seen say
// "split": more pairs can only raise Gmax and lower Gmin, so the answer stays. (A similarity that
// is checked on every value it returns gets every pair.)
template <class PairG>
bool split_by_ratio(std::size_t n, double x, PairG&& g, bool every_pair = false) {
  if (n < 2) return false;
  double gmax = 0, gmin = std::numeric_limits<double>::infinity();
  const auto above = [&] { return gmax > 0 && (gmin == 0 || gmax / gmin > x); };
  for (std::size_t b = 1; b < n; ++b)
    for (std::size_t a = 0; a < b; ++a) {
      const double v = g(a, b);
      gmax = std::max(gmax, v);
      gmin = std::min(gmin, v);
      if (!every_pair && above()) return true;
    }
  return above();
}

// split_by_ratio over the G-statistics (g_statistic) of the given histograms of `bins` counts.
bool should_split(const std::vector<const std::uint32_t*>& histograms, std::size_t bins, double x);

// Tiles the map with Smax blocks anchored at voxel (0,0,0), clipped by the map's far faces, and
// splits each recursively into octants down to Smin. Leaves come out in a fixed order
// (top blocks in x-fastest order, octants depth-first), whatever the thread count.
std::vector<Block> divide(const Grid& grid, const TextureMap& texture, const Params& params,
                          const kernels::Table& k = kernels::active());

// Histogram of the texture codes of block b (h: `bins` counts, overwritten); kNoTexture voxels
// are not counted. The division's own counting, exposed for unit tests.
void count_codes(const TextureMap& texture, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h,
                 const kernels::Table& k = kernels::active());

}  // namespace occseg
