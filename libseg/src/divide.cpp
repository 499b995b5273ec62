#include "occseg/divide.hpp"

#include <algorithm>
#include <limits>

#include "occseg/error.hpp"
#include "occseg/histogram.hpp"
#include "occseg/parallel.hpp"

namespace occseg {

bool should_split(const std::vector<const std::uint32_t*>& h, std::size_t bins, double x) {
  if (h.size() < 2) return false;
  double gmax = 0, gmin = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < h.size(); ++a)
    for (std::size_t b = a + 1; b < h.size(); ++b) {
      const double g = g_statistic(h[a], h[b], bins);
      gmax = std::max(gmax, g);
      gmin = std::min(gmin, g);
    }
  if (gmax == 0) return false;  // all pairs identical: uniform texture
  if (gmin == 0) return true;   // infinite ratio
  return gmax / gmin > x;
}

namespace {

struct Divider {
  const Grid& grid;
  const TextureMap& tex;
  const Params& params;

  void histogram(const Block& b, std::vector<std::uint32_t>& h) const {
    std::fill(h.begin(), h.end(), 0u);
    const std::size_t nx = grid.dims.nx, ny = grid.dims.ny;
    for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
      for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y) {
        const std::uint16_t* row = tex.codes.data() + nx * (y + ny * z);
        for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x)
          if (row[x] != kNoTexture) ++h[row[x]];
      }
  }

  // Octants of a block of nominal edge `size` whose low corner is a multiple of `size`.
  static std::vector<Block> octants(const Block& b, std::uint32_t size) {
    const std::uint32_t half = size / 2;
    std::vector<Block> out;
    for (int k = 0; k < 8; ++k) {
      Block c;
      bool empty = false;
      for (int a = 0; a < 3; ++a) {
        const std::uint32_t mid = b.lo[a] + half;
        const bool upper = (k >> a) & 1;
        c.lo[a] = upper ? mid : b.lo[a];
        c.hi[a] = upper ? b.hi[a] : std::min(mid, b.hi[a]);
        if (c.lo[a] >= c.hi[a]) empty = true;
      }
      if (!empty) out.push_back(c);
    }
    return out;
  }

  void run(const Block& b, std::uint32_t size, std::vector<Block>& leaves) const {
    if (size <= static_cast<std::uint32_t>(params.smin)) {
      leaves.push_back(b);
      return;
    }
    const std::vector<Block> kids = octants(b, size);
    if (kids.size() == 1) {  // the map edge left a single octant: nothing to compare yet
      run(kids[0], size / 2, leaves);
      return;
    }
    const std::size_t bins = static_cast<std::size_t>(tex.code_count());
    std::vector<std::vector<std::uint32_t>> hist(kids.size(), std::vector<std::uint32_t>(bins));
    std::vector<const std::uint32_t*> used;
    for (std::size_t k = 0; k < kids.size(); ++k) {
      histogram(kids[k], hist[k]);
      bool any = false;
      for (auto v : hist[k]) any = any || v;
      if (any) used.push_back(hist[k].data());  // octants of border voxels only carry no texture
    }
    if (!should_split(used, bins, params.split_ratio)) {
      leaves.push_back(b);
      return;
    }
    for (const Block& k : kids) run(k, size / 2, leaves);
  }
};

}  // namespace

std::vector<Block> divide(const Grid& grid, const TextureMap& tex, const Params& params) {
  const std::uint32_t s = static_cast<std::uint32_t>(params.smax);
  const std::size_t n[3] = {grid.dims.nx, grid.dims.ny, grid.dims.nz};
  std::size_t t[3];
  for (int a = 0; a < 3; ++a) t[a] = (n[a] + s - 1) / s;
  const std::size_t tops = t[0] * t[1] * t[2];
  std::vector<std::vector<Block>> per_top(tops);
  const Divider d{grid, tex, params};
  parallel_for(tops, params.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::size_t c[3] = {i % t[0], (i / t[0]) % t[1], i / (t[0] * t[1])};
      Block blk;
      for (int a = 0; a < 3; ++a) {
        blk.lo[a] = static_cast<std::uint32_t>(c[a] * s);
        blk.hi[a] = static_cast<std::uint32_t>(std::min<std::size_t>(n[a], (c[a] + 1) * s));
      }
      d.run(blk, s, per_top[i]);
    }
  });
  std::vector<Block> leaves;
  for (auto& v : per_top) leaves.insert(leaves.end(), v.begin(), v.end());
  return leaves;
}

}  // namespace occseg
