#include "occseg/departures.hpp"

#include <algorithm>
#include <mutex>

#include "occseg/parallel.hpp"
#include "huge_pages.hpp"
#include "occseg/refine.hpp"

namespace occseg {

namespace {

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);

// out[x] = in[x] op in[x+d] for x in [0, n): one vectorisable step of a box filter.
__attribute__((target_clones("avx2", "default")))
void and_rows(std::uint8_t* out, const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) out[x] = a[x] & b[x];
}
__attribute__((target_clones("avx2", "default")))
void or_rows(std::uint8_t* out, const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  for (std::size_t x = 0; x < n; ++x) out[x] = a[x] | b[x];
}

// One axis of a box erosion (AND) or dilation (OR) of radius r, from `in` to `out`. The window is
// clipped by the map: erosion counts the outside as 1 and dilation as 0, as the opening needs.
void box_pass(const std::uint8_t* in, std::uint8_t* out, const Dims& d, int axis, int r, bool erode, int threads) {
  auto op = erode ? and_rows : or_rows;
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz;
  const std::size_t R = static_cast<std::size_t>(r);
  if (axis == 0) {
    parallel_for_dynamic(ny * nz, threads, [&](std::size_t r0, std::size_t r1) {
      for (std::size_t row = r0; row < r1; ++row) {
        const std::uint8_t* a = in + row * nx;
        std::uint8_t* o = out + row * nx;
        std::copy(a, a + nx, o);
        for (std::size_t k = 1; k <= R && k < nx; ++k) {
          op(o, o, a + k, nx - k);  // o[x] op= a[x + k]
          op(o + k, o + k, a, nx - k);  // o[x] op= a[x - k]
        }
      }
    });
    return;
  }
  // y or z: whole rows combine with rows k voxels away along the axis.
  const std::size_t len = axis == 1 ? ny : nz, planes = axis == 1 ? nz : ny;
  const std::size_t row = axis == 1 ? nx : nx * ny;  // distance between rows along the axis
  const std::size_t plane = axis == 1 ? nx * ny : nx;
  parallel_for_dynamic(planes, threads, [&](std::size_t p0, std::size_t p1) {
    for (std::size_t pl = p0; pl < p1; ++pl)
      for (std::size_t k = 0; k < len; ++k) {
        const std::size_t base = pl * plane;
        std::uint8_t* o = out + base + k * row;
        const std::size_t lo = k >= R ? k - R : 0, hi = std::min(len - 1, k + R);
        std::copy(in + base + lo * row, in + base + lo * row + nx, o);
        for (std::size_t j = lo + 1; j <= hi; ++j) op(o, o, in + base + j * row, nx);
      }
  });
}

__attribute__((target_clones("avx2", "default")))
void half_mask(const std::uint8_t* own, std::uint8_t* m, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) m[i] = own[i] == kUnknown;
}

// m[i] &= own[i] is at 0.5.
__attribute__((target_clones("avx2", "default")))
void keep_half(std::uint8_t* __restrict m, const std::uint8_t* __restrict own, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) m[i] = static_cast<std::uint8_t>(m[i] & (own[i] == kUnknown));
}

// The per-voxel rules on one row of voxels (x in [0, n)); xm/xp, ym/yp, zm/zp are the own states
// of the neighbours, with `none` (all free) rows standing in outside the map.
inline std::uint8_t rule(std::uint8_t s, std::uint8_t o, std::uint8_t region, bool touches) {
  const std::uint8_t gap = ((s == kFree) & touches) ? kUnknown : s;
  return o != kUnknown ? o : (region ? kUnknown : gap);
}

// Applies the rules to one row and returns false when it holds no seed of the gap flood (a gap
// voxel the rules left unknown that touches an occupied voxel), so that only the other rows are
// searched for seeds. Branch-free, so the whole row vectorises.
__attribute__((target_clones("avx2", "default")))
bool rules_row(std::uint8_t* __restrict st, const std::uint8_t* __restrict own, const std::uint8_t* __restrict region,
               const std::uint8_t* __restrict ym, const std::uint8_t* __restrict yp, const std::uint8_t* __restrict zm,
               const std::uint8_t* __restrict zp, std::size_t n) {
  auto across = [&](std::size_t x) {  // occupied neighbour in y or z
    return (ym[x] == kOccupied) | (yp[x] == kOccupied) | (zm[x] == kOccupied) | (zp[x] == kOccupied);
  };
  auto seed = [&](std::size_t x, bool touches) {
    return static_cast<std::uint8_t>((own[x] == kUnknown) & (region[x] == 0) & touches & (st[x] == kUnknown));
  };
  if (n == 1) {
    st[0] = rule(st[0], own[0], region[0], across(0));
    return seed(0, across(0));
  }
  for (std::size_t x = 1; x + 1 < n; ++x) {
    const bool touches = (own[x - 1] == kOccupied) | (own[x + 1] == kOccupied) | across(x);
    st[x] = rule(st[x], own[x], region[x], touches);
  }
  // A second, cheap pass for the flag (GCC 12 does not vectorise the loop above with a reduction
  // in it): a superset of the seeds, gap voxels left unknown; the caller checks the neighbours.
  std::uint8_t any = 0;
  for (std::size_t x = 1; x + 1 < n; ++x)
    any |= static_cast<std::uint8_t>((own[x] == kUnknown) & (region[x] == 0) & (st[x] == kUnknown));
  const bool t0 = (own[1] == kOccupied) | across(0), tn = (own[n - 2] == kOccupied) | across(n - 1);
  st[0] = rule(st[0], own[0], region[0], t0);
  st[n - 1] = rule(st[n - 1], own[n - 1], region[n - 1], tn);
  return any | seed(0, t0) | seed(n - 1, tn);
}

}  // namespace

std::vector<std::uint8_t> unknown_regions(const std::vector<std::uint8_t>& own, const Dims& d, const Params& params) {
  std::vector<std::uint8_t> m;
  resize_huge(m, own.size());
  const std::size_t chunk = 1 << 16;
  parallel_for((m.size() + chunk - 1) / chunk, params.threads, [&](std::size_t c0, std::size_t c1) {
    const std::size_t b = c0 * chunk, e = std::min(m.size(), c1 * chunk);
    half_mask(own.data() + b, m.data() + b, e - b);
  });
  const int r = params.gap_radius;
  if (r <= 0) return m;
  // Opening = erosion then dilation, each separable into three axis passes (ping-pong buffers).
  std::vector<std::uint8_t> t;
  resize_huge(t, m.size());
  std::uint8_t* a = m.data();
  std::uint8_t* b = t.data();
  for (int pass = 0; pass < 6; ++pass) {
    box_pass(a, b, d, pass % 3, r, pass < 3, params.threads);
    std::swap(a, b);
  }
  // Six passes end in m again. The opening only shrinks the mask; keep it on 0.5 voxels anyway.
  parallel_for((m.size() + chunk - 1) / chunk, params.threads, [&](std::size_t c0, std::size_t c1) {
    const std::size_t b = c0 * chunk, e = std::min(m.size(), c1 * chunk);
    keep_half(m.data() + b, own.data() + b, e - b);
  });
  return m;
}

namespace {

// Rule 3 carried through whole gaps: every gap voxel the texture calls free that is 6-connected,
// through gap voxels, to a gap voxel touching an occupied voxel becomes unknown. The unobserved
// inside of a thin structure (a table top seen only edge-on) is such a gap; without this it would
// be labelled free everywhere but along its rim. `queue` holds the seeds (gap voxels left unknown
// that touch an occupied voxel), in any order: the result is a set (connected components), so it
// does not depend on visiting order.
void flood_gaps_from_objects(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own,
                             const std::vector<std::uint8_t>& region, const Dims& d, std::vector<std::size_t>& queue) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sz = nx * ny;
  auto gap = [&](std::size_t i) { return own[i] == kUnknown && !region[i]; };
  while (!queue.empty()) {
    const std::size_t i = queue.back();
    queue.pop_back();
    const std::size_t x = i % nx, y = (i / nx) % ny, z = i / sz;
    auto visit = [&](std::size_t j) {
      if (st[j] == kFree && gap(j)) {
        st[j] = kUnknown;
        queue.push_back(j);
      }
    };
    if (x > 0) visit(i - 1);
    if (x + 1 < nx) visit(i + 1);
    if (y > 0) visit(i - nx);
    if (y + 1 < ny) visit(i + nx);
    if (z > 0) visit(i - sz);
    if (z + 1 < nz) visit(i + sz);
  }
}

}  // namespace

void apply_voxel_rules(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                       const Params& params) {
  const std::vector<std::uint8_t> region = unknown_regions(own, d, params);
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sz = nx * ny;
  const std::vector<std::uint8_t> none(nx, kFree);  // outside the map: no occupied neighbour
  // Reads only own states and each voxel's own entry of st, so rows are independent. Rows that
  // hold seeds of the gap flood are searched for them on the way, slab by slab.
  std::vector<std::size_t> seeds;
  std::mutex seeds_mutex;
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::size_t> mine;
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t i = nx * (y + ny * z);
        const std::uint8_t* o = own.data() + i;
        if (!rules_row(st.data() + i, o, region.data() + i, y > 0 ? o - nx : none.data(),
                       y + 1 < ny ? o + nx : none.data(), z > 0 ? o - sz : none.data(),
                       z + 1 < nz ? o + sz : none.data(), nx))
          continue;
        for (std::size_t x = 0; x < nx; ++x) {
          const std::size_t j = i + x;
          if (st[j] != kUnknown || own[j] != kUnknown || region[j]) continue;
          const bool touches = (x > 0 && own[j - 1] == kOccupied) || (x + 1 < nx && own[j + 1] == kOccupied) ||
                               (y > 0 && own[j - nx] == kOccupied) || (y + 1 < ny && own[j + nx] == kOccupied) ||
                               (z > 0 && own[j - sz] == kOccupied) || (z + 1 < nz && own[j + sz] == kOccupied);
          if (touches) mine.push_back(j);
        }
      }
    std::lock_guard<std::mutex> lock(seeds_mutex);
    seeds.insert(seeds.end(), mine.begin(), mine.end());
  });
  flood_gaps_from_objects(st, own, region, d, seeds);
}

std::vector<std::uint8_t> unknown_regions(const Grid& g, const Params& params) {
  return unknown_regions(own_states(g, params), g.dims, params);
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  apply_voxel_rules(st, own_states(g, params), g.dims, params);
}

}  // namespace occseg
