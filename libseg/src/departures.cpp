#include "occseg/departures.hpp"

#include <algorithm>

#include "occseg/parallel.hpp"

namespace occseg {

namespace {

// In-place running min (erode) or max (dilate) of a 0/1 mask over a window of radius r along one
// axis. Outside the map counts as `outside`.
void box_pass(std::vector<std::uint8_t>& m, const Dims& d, int axis, int r, bool erode, int threads) {
  const std::size_t n[3] = {d.nx, d.ny, d.nz};
  const std::size_t s[3] = {1, d.nx, d.nx * d.ny};
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  const std::size_t len = n[axis];
  const std::uint8_t outside = erode ? 1 : 0;
  parallel_for(n[c], threads, [&](std::size_t c0, std::size_t c1) {
    std::vector<std::uint8_t> line(len);
    std::vector<std::size_t> prefix(len + 1);
    for (std::size_t ic = c0; ic < c1; ++ic)
      for (std::size_t ib = 0; ib < n[b]; ++ib) {
        const std::size_t first = ib * s[b] + ic * s[c];
        prefix[0] = 0;
        for (std::size_t k = 0; k < len; ++k) {
          line[k] = m[first + k * s[axis]];
          prefix[k + 1] = prefix[k] + line[k];
        }
        for (std::size_t k = 0; k < len; ++k) {
          const std::size_t lo = k >= static_cast<std::size_t>(r) ? k - r : 0;
          const std::size_t hi = std::min(len, k + r + 1);
          const std::size_t ones = prefix[hi] - prefix[lo];
          const std::size_t missing = static_cast<std::size_t>(2 * r + 1) - (hi - lo);  // outside
          std::uint8_t v;
          if (erode) v = (ones == hi - lo && (outside || missing == 0)) ? 1 : 0;
          else v = (ones > 0 || (outside && missing > 0)) ? 1 : 0;
          m[first + k * s[axis]] = v;
        }
      }
  });
}

}  // namespace

std::vector<std::uint8_t> unknown_regions(const Grid& g, const Params& params) {
  std::vector<std::uint8_t> m(g.dims.count());
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = params.at_half(g.p[i]) ? 1 : 0;
  const int r = params.gap_radius;
  if (r <= 0) return m;
  for (int a = 0; a < 3; ++a) box_pass(m, g.dims, a, r, true, params.threads);
  for (int a = 0; a < 3; ++a) box_pass(m, g.dims, a, r, false, params.threads);
  // Opening can only shrink the mask, but guard against dilation leaking onto non-0.5 voxels.
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = m[i] && params.at_half(g.p[i]);
  return m;
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  const std::vector<std::uint8_t> region = unknown_regions(g, params);
  const auto kFree = static_cast<std::uint8_t>(State::free);
  const auto kUnknown = static_cast<std::uint8_t>(State::unknown);
  const auto kOcc = static_cast<std::uint8_t>(State::occupied);
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, nz = g.dims.nz, sz = nx * ny;
  const float* p = g.p.data();
  // Reads st only at 0.5 voxels' neighbours whose own state is occupied: these never change, so
  // the in-place update does not depend on visiting order.
  parallel_for(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x) {
          const std::size_t i = x + nx * (y + ny * z);
          const State own = params.state_of(p[i]);
          if (own != State::unknown) {
            st[i] = static_cast<std::uint8_t>(own);
          } else if (region[i]) {
            st[i] = kUnknown;
          } else if (st[i] == kFree) {
            const bool touches =
                (x > 0 && p[i - 1] > params.occupied_above) || (x + 1 < nx && p[i + 1] > params.occupied_above) ||
                (y > 0 && p[i - nx] > params.occupied_above) || (y + 1 < ny && p[i + nx] > params.occupied_above) ||
                (z > 0 && p[i - sz] > params.occupied_above) || (z + 1 < nz && p[i + sz] > params.occupied_above);
            if (touches) st[i] = kUnknown;
          }
        }
  });
  (void)kOcc;
}

}  // namespace occseg
