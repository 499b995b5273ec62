#include "occseg/texture.hpp"

#include <algorithm>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"

namespace occseg {

TextureUnit texture_unit(double centre, const double n[6], unsigned present) {
  TextureUnit u;
  double sum1 = 0, sum0 = 0;
  int n1 = 0, n0 = 0;
  for (int i = 0; i < 6; ++i) {
    if (!(present & (1u << i))) continue;
    if (n[i] >= centre) {
      u.lbp = static_cast<std::uint8_t>(u.lbp | (1u << i));
      sum1 += n[i];
      ++n1;
    } else {
      sum0 += n[i];
      ++n0;
    }
  }
  u.contrast = (n1 && n0) ? sum1 / n1 - sum0 / n0 : 0.0;
  return u;
}

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

namespace {

// Visits the texture unit of every interior voxel of z-slices [z0, z1). An axis of size 1 is
// not a border: its neighbours are simply absent (2D maps keep a 4-neighbour texture).
template <class F>
void for_each_unit(const Grid& g, std::size_t z0, std::size_t z1, F&& f) {
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, nz = g.dims.nz;
  const std::ptrdiff_t sy = static_cast<std::ptrdiff_t>(nx), sz = static_cast<std::ptrdiff_t>(nx * ny);
  const bool fx = nx == 1, fy = ny == 1, fz = nz == 1;
  const unsigned present = (fx ? 0u : 3u) | (fy ? 0u : 12u) | (fz ? 0u : 48u);
  const float* p = g.p.data();
  for (std::size_t z = z0; z < z1; ++z) {
    const bool bz = !fz && (z == 0 || z == nz - 1);
    for (std::size_t y = 0; y < ny; ++y) {
      const bool by = !fy && (y == 0 || y == ny - 1);
      for (std::size_t x = 0; x < nx; ++x) {
        const std::size_t i = x + nx * (y + ny * z);
        if (bz || by || (!fx && (x == 0 || x == nx - 1))) {
          f(i, nullptr);
          continue;
        }
        double nb[6] = {0, 0, 0, 0, 0, 0};
        if (!fx) { nb[0] = p[i - 1]; nb[1] = p[i + 1]; }
        if (!fy) { nb[2] = p[i - sy]; nb[3] = p[i + sy]; }
        if (!fz) { nb[4] = p[i - sz]; nb[5] = p[i + sz]; }
        const TextureUnit u = texture_unit(p[i], nb, present);
        f(i, &u);
      }
    }
  }
}

}  // namespace

TextureMap compute_texture(const Grid& grid, int contrast_bins, int threads) {
  if (contrast_bins < 2 || contrast_bins > 64)
    throw Error(Status::invalid_argument, "contrast_bins = " + std::to_string(contrast_bins) +
                                              " is outside [2, 64]");
  const std::size_t nz = grid.dims.nz;
  const int t = std::max(1, std::min<int>(resolve_threads(threads), static_cast<int>(nz)));
  // Pass 1: distribution of non-zero contrasts on the fine grid, summed in a fixed order.
  std::vector<std::vector<std::uint64_t>> part(t, std::vector<std::uint64_t>(ContrastQuantizer::kFine, 0));
  parallel_for(static_cast<std::size_t>(t), t, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k)
      for_each_unit(grid, nz * k / t, nz * (k + 1) / t, [&](std::size_t, const TextureUnit* u) {
        if (u && u->contrast > 0) ++part[k][ContrastQuantizer::fine_step(u->contrast)];
      });
  });
  std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
  for (auto& h : part)
    for (int f = 0; f < ContrastQuantizer::kFine; ++f) fine[f] += h[f];
  const ContrastQuantizer q(contrast_bins, fine);
  // Pass 2: codes.
  TextureMap tm;
  tm.bins = contrast_bins;
  tm.codes.resize(grid.dims.count());
  parallel_for(nz, threads, [&](std::size_t z0, std::size_t z1) {
    for_each_unit(grid, z0, z1, [&](std::size_t i, const TextureUnit* u) {
      tm.codes[i] = u ? static_cast<std::uint16_t>(u->lbp * contrast_bins + q.level(u->contrast)) : kNoTexture;
    });
  });
  return tm;
}

}  // namespace occseg
