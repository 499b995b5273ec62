// The pipeline as first written (scalar, serial): see reference.hpp.
#include "reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>

namespace occseg::reference {

namespace {

constexpr std::uint8_t kFree = 0, kUnknown = 1, kOccupied = 2;

// Section 3.3's six scans, in the order the library documents: left-right, right-left along x,
// then y, then z.
struct ScanDirection {
  int axis;  // 0, 1, 2: x, y, z
  int step;  // +1 or -1
};
constexpr ScanDirection kSixDirections[6] = {{0, +1}, {0, -1}, {1, +1}, {1, -1}, {2, +1}, {2, -1}};

// Section 2.2's texture unit of one voxel: neighbours >= the centre are 1 (bit i of the LBP for
// neighbour i: x-1, x+1, y-1, y+1, z-1, z+1), the contrast is mean(1s) - mean(0s), 0 when one
// side is empty. Neighbours outside `present` (an axis of size 1) take no part.
struct Unit {
  std::uint8_t lbp = 0;
  double contrast = 0;
};
Unit texture_unit(double centre, const double n[6], unsigned present) {
  Unit u;
  double ones = 0, zeros = 0;
  int n1 = 0, n0 = 0;
  for (int i = 0; i < 6; ++i) {
    if (!(present >> i & 1u)) continue;
    if (n[i] >= centre) {
      u.lbp = static_cast<std::uint8_t>(u.lbp + (1u << i));
      ones += n[i];
      ++n1;
    } else {
      zeros += n[i];
      ++n0;
    }
  }
  if (n1 > 0 && n0 > 0) u.contrast = ones / n1 - zeros / n0;
  return u;
}

// The contrast levels (docs/algorithm.md): level 0 is C = 0; the non-zero contrasts, measured in
// steps of 1/4096 (clamped to [0, 4095]), are split into bins - 1 classes of equal frequency: the
// k-th cut is the first step whose cumulative count reaches k / (bins - 1) of the total, and a
// step's level is 1 plus the number of cuts below it.
constexpr int kSteps = 4096;
int step_of(double c) { return std::min(kSteps - 1, std::max(0, static_cast<int>(c * kSteps))); }
std::vector<int> level_of_steps(const std::vector<std::uint64_t>& count, int bins) {
  const std::uint64_t total = [&] {
    std::uint64_t t = 0;
    for (auto c : count) t += c;
    return t;
  }();
  const std::uint64_t classes = static_cast<std::uint64_t>(bins - 1);
  std::vector<int> cuts;
  for (std::uint64_t k = 1; k < classes && total > 0; ++k) {
    std::uint64_t cum = 0;
    int f = 0;
    while (f < kSteps && (cum += count[f]) * classes < total * k) ++f;
    if (f < kSteps) cuts.push_back(f);
  }
  std::vector<int> level(kSteps, 1);
  for (int f = 0; f < kSteps; ++f)
    for (int c : cuts) level[f] += c < f;
  return level;
}

template <class F>
void for_each_unit(const Grid& g, F&& f) {
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, nz = g.dims.nz;
  const std::ptrdiff_t sy = static_cast<std::ptrdiff_t>(nx), sz = static_cast<std::ptrdiff_t>(nx * ny);
  const bool fx = nx == 1, fy = ny == 1, fz = nz == 1;
  const unsigned present = (fx ? 0u : 3u) | (fy ? 0u : 12u) | (fz ? 0u : 48u);
  const float* p = g.p.data();
  for (std::size_t z = 0; z < nz; ++z) {
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
        const Unit u = texture_unit(p[i], nb, present);
        f(i, &u);
      }
    }
  }
}

inline double xlogx(double v) { return v > 0 ? v * std::log(v) : 0.0; }

bool should_split(const std::vector<const std::uint32_t*>& h, std::size_t bins, double x) {
  if (h.size() < 2) return false;
  double gmax = 0, gmin = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < h.size(); ++a)
    for (std::size_t b = a + 1; b < h.size(); ++b) {
      const double g = reference::g_statistic(h[a], h[b], bins);
      gmax = std::max(gmax, g);
      gmin = std::min(gmin, g);
    }
  if (gmax == 0) return false;
  if (gmin == 0) return true;
  return gmax / gmin > x;
}

struct Divider {
  const Grid& grid;
  const TextureMap& tex;
  const Params& params;

  void histogram(const Block& b, std::vector<std::uint32_t>& h) const {
    std::fill(h.begin(), h.end(), 0u);
    for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
      for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
        for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) {
          const std::uint16_t c = tex.codes[grid.index(x, y, z)];
          if (c != kNoTexture) ++h[c];
        }
  }

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
    if (kids.size() == 1) {
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
      if (any) used.push_back(hist[k].data());
    }
    if (!should_split(used, bins, params.split_ratio)) {
      leaves.push_back(b);
      return;
    }
    for (const Block& k : kids) run(k, size / 2, leaves);
  }
};

// Every line along `dir`, in a fixed order.
template <class F>
void for_each_line(const Grid& g, ScanDirection dir, F&& fn) {
  const std::size_t n[3] = {g.dims.nx, g.dims.ny, g.dims.nz};
  const std::ptrdiff_t s[3] = {1, static_cast<std::ptrdiff_t>(n[0]), static_cast<std::ptrdiff_t>(n[0] * n[1])};
  const int a = dir.axis, b = (a + 1) % 3, c = (a + 2) % 3;
  const std::size_t len = n[a];
  const std::ptrdiff_t stride = s[a] * dir.step;
  for (std::size_t ic = 0; ic < n[c]; ++ic)
    for (std::size_t ib = 0; ib < n[b]; ++ib) {
      std::ptrdiff_t first = static_cast<std::ptrdiff_t>(ib) * s[b] + static_cast<std::ptrdiff_t>(ic) * s[c];
      if (dir.step < 0) first += static_cast<std::ptrdiff_t>(len - 1) * s[a];
      fn(first, stride, len);
    }
}

void classify(const float* p, int n, std::uint8_t from, const Params& params, bool* reassign) {
  bool low = false, high = false;
  for (int k = 0; k < n; ++k) {
    low = low || p[k] < params.free_below;
    high = high || p[k] > params.occupied_above;
    reassign[k] = false;
  }
  const bool other = (from == kFree) ? low : high;
  const bool own = (from == kFree) ? high : low;
  if (!other) return;
  for (int k = 0; k < n; ++k)
    reassign[k] = !own || ((from == kFree) ? !(p[k] > params.occupied_above) : !(p[k] < params.free_below));
}

std::vector<std::uint8_t> opening(const Grid& g, const Params& params) {
  const Dims& d = g.dims;
  std::vector<std::uint8_t> m(d.count());
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = params.at_half(g.p[i]) ? 1 : 0;
  const int r = params.gap_radius;
  if (r <= 0) return m;
  const std::size_t n[3] = {d.nx, d.ny, d.nz};
  const std::size_t s[3] = {1, d.nx, d.nx * d.ny};
  for (int pass = 0; pass < 6; ++pass) {
    const int axis = pass % 3;
    const bool erode = pass < 3;
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    const std::size_t len = n[axis];
    std::vector<std::uint8_t> line(len);
    std::vector<std::size_t> prefix(len + 1);
    for (std::size_t ic = 0; ic < n[c]; ++ic)
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
          const std::size_t missing = static_cast<std::size_t>(2 * r + 1) - (hi - lo);
          // Erosion counts outside the map as 0.5 (keeps a voxel whose in-map window is all 0.5);
          // dilation counts it as not 0.5.
          (void)missing;
          m[first + k * s[axis]] = erode ? (ones == hi - lo) : (ones > 0);
        }
      }
  }
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = m[i] && params.at_half(g.p[i]);
  return m;
}

inline std::uint32_t find(std::uint32_t* parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

inline void unite(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
  a = find(parent, a);
  b = find(parent, b);
  if (a == b) return;
  if (a < b) std::swap(a, b);
  parent[a] = b;
}

}  // namespace

TextureMap texture(const Grid& grid, int bins) {
  std::vector<std::uint64_t> fine(kSteps, 0);
  for_each_unit(grid, [&](std::size_t, const Unit* u) {
    if (u && u->contrast > 0) ++fine[step_of(u->contrast)];
  });
  const std::vector<int> level = level_of_steps(fine, bins);
  TextureMap tm;
  tm.bins = bins;
  tm.codes.resize(grid.dims.count());
  for_each_unit(grid, [&](std::size_t i, const Unit* u) {
    const int c = !u || u->contrast <= 0 ? 0 : level[step_of(u->contrast)];
    tm.codes[i] = u ? static_cast<std::uint16_t>(u->lbp * bins + c) : kNoTexture;
  });
  return tm;
}

// The documented order of one sum: its non-zero terms t_0, t_1, ... in bin order, t_k added into
// lane k mod 8, the lanes then added as ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)).
double eight_lanes(const std::vector<double>& terms) {
  double l[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (std::size_t k = 0; k < terms.size(); ++k) l[k % 8] += terms[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins) {
  // The documented summation: sum f ln f of each histogram over its non-empty bins, the two added;
  // the joint term over the bins where either is non-empty; each sum in eight lanes.
  std::vector<double> ts, tm, tj;
  double ns = 0, nm = 0;
  for (std::size_t i = 0; i < bins; ++i) {
    const double a = s[i], b = m[i];
    if (a > 0) ts.push_back(xlogx(a));
    if (b > 0) tm.push_back(xlogx(b));
    if (a + b > 0) tj.push_back(xlogx(a + b));
    ns += a;
    nm += b;
  }
  const double cs = eight_lanes(ts), cm = eight_lanes(tm), joint = eight_lanes(tj);
  const double g = 2.0 * ((cs + cm) - xlogx(ns) - xlogx(nm) - joint + xlogx(ns + nm));
  return g > 1e-9 * (ns + nm) ? g : 0.0;
}

std::vector<Block> divide(const Grid& grid, const TextureMap& tex, const Params& params) {
  const std::uint32_t s = static_cast<std::uint32_t>(params.smax);
  const std::size_t n[3] = {grid.dims.nx, grid.dims.ny, grid.dims.nz};
  std::vector<Block> leaves;
  const Divider d{grid, tex, params};
  for (std::size_t cz = 0; cz * s < n[2]; ++cz)
    for (std::size_t cy = 0; cy * s < n[1]; ++cy)
      for (std::size_t cx = 0; cx * s < n[0]; ++cx) {
        const std::size_t c[3] = {cx, cy, cz};
        Block blk;
        for (int a = 0; a < 3; ++a) {
          blk.lo[a] = static_cast<std::uint32_t>(c[a] * s);
          blk.hi[a] = static_cast<std::uint32_t>(std::min<std::size_t>(n[a], (c[a] + 1) * s));
        }
        d.run(blk, s, leaves);
      }
  return leaves;
}

std::vector<std::uint8_t> create(const Grid& grid, const std::vector<Block>& blocks, const Params& params) {
  std::vector<std::uint8_t> st(grid.dims.count());
  for (const Block& b : blocks) {
    // The documented order: by cells of 8^3 voxels (anchored at voxel 0), each cell's voxels of
    // the block in scan order, the cells in scan order.
    double sum = 0;
    for (std::uint32_t cz = b.lo[2] / 8 * 8; cz < b.hi[2]; cz += 8)  // the cells it meets
      for (std::uint32_t cy = b.lo[1] / 8 * 8; cy < b.hi[1]; cy += 8)
        for (std::uint32_t cx = b.lo[0] / 8 * 8; cx < b.hi[0]; cx += 8) {
          double part = 0;
          for (std::uint32_t z = cz; z < cz + 8; ++z)
            for (std::uint32_t y = cy; y < cy + 8; ++y)
              for (std::uint32_t x = cx; x < cx + 8; ++x)
                if (x >= b.lo[0] && x < b.hi[0] && y >= b.lo[1] && y < b.hi[1] && z >= b.lo[2] && z < b.hi[2])
                  part += grid.at(x, y, z);
          sum += part;
        }
    const auto s = static_cast<std::uint8_t>(params.state_of(sum / static_cast<double>(b.volume())));
    for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
      for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
        for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) st[grid.index(x, y, z)] = s;
  }
  return st;
}

void refine_unknown(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  for (const ScanDirection dir : kSixDirections)
    for_each_line(g, dir, [&](std::ptrdiff_t i, std::ptrdiff_t stride, std::size_t len) {
      std::uint8_t prev = st[i];
      for (std::size_t k = 1; k < len; ++k) {
        i += stride;
        if (prev == kUnknown && st[i] == kFree && params.at_half(g.p[i])) st[i] = kUnknown;
        prev = st[i];
      }
    });
}

void refine_boundaries(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  const int look = std::max(1, params.lookahead);
  std::vector<float> win(look);
  std::vector<std::ptrdiff_t> at(look);
  std::unique_ptr<bool[]> re(new bool[look]);
  for (int pass = 0; pass < params.refine_passes; ++pass)
    for (const ScanDirection dir : kSixDirections)
      for_each_line(g, dir, [&](std::ptrdiff_t first, std::ptrdiff_t stride, std::size_t len) {
        std::size_t k = 1;
        while (k < len) {
          const std::ptrdiff_t i = first + static_cast<std::ptrdiff_t>(k) * stride;
          const std::uint8_t a = st[i - stride], s = st[i];
          if (!((a == kFree && s == kOccupied) || (a == kOccupied && s == kFree))) {
            ++k;
            continue;
          }
          int n = 0;
          while (n < look && k + n < len && st[i + n * stride] == s) {
            at[n] = i + n * stride;
            win[n] = g.p[at[n]];
            ++n;
          }
          classify(win.data(), n, a, params, re.get());
          for (int w = 0; w < n; ++w)
            if (re[w]) st[at[w]] = a;
          k += static_cast<std::size_t>(n);  // resume after the window
        }
      });
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  const std::vector<std::uint8_t> region = opening(g, params);
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, nz = g.dims.nz, sz = nx * ny;
  const float* p = g.p.data();
  const double hi = params.occupied_above;
  for (std::size_t z = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const std::size_t i = x + nx * (y + ny * z);
        const State own = params.state_of(p[i]);
        if (own != State::unknown) {
          st[i] = static_cast<std::uint8_t>(own);
        } else if (region[i]) {
          st[i] = kUnknown;
        } else if (st[i] == kFree) {
          const bool touches = (x > 0 && p[i - 1] > hi) || (x + 1 < nx && p[i + 1] > hi) ||
                               (y > 0 && p[i - nx] > hi) || (y + 1 < ny && p[i + nx] > hi) ||
                               (z > 0 && p[i - sz] > hi) || (z + 1 < nz && p[i + sz] > hi);
          if (touches) st[i] = kUnknown;
        }
      }
  // Gaps connected to an object: seeds are gap voxels left unknown that touch an occupied voxel;
  // free gap voxels next to a marked one are marked, sweep after sweep, until nothing changes.
  auto gap = [&](std::size_t i) { return params.state_of(p[i]) == State::unknown && !region[i]; };
  auto occ = [&](std::size_t i) { return p[i] > hi; };
  std::vector<std::uint8_t> mark(st.size(), 0);
  for (std::size_t z = 0, i = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x, ++i)
        mark[i] = st[i] == kUnknown && gap(i) &&
                  ((x > 0 && occ(i - 1)) || (x + 1 < nx && occ(i + 1)) || (y > 0 && occ(i - nx)) ||
                   (y + 1 < ny && occ(i + nx)) || (z > 0 && occ(i - sz)) || (z + 1 < nz && occ(i + sz)));
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t z = 0, i = 0; z < nz; ++z)
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x, ++i) {
          if (mark[i] || st[i] != kFree || !gap(i)) continue;
          if ((x > 0 && mark[i - 1]) || (x + 1 < nx && mark[i + 1]) || (y > 0 && mark[i - nx]) ||
              (y + 1 < ny && mark[i + nx]) || (z > 0 && mark[i - sz]) || (z + 1 < nz && mark[i + sz])) {
            mark[i] = 1;
            changed = true;
          }
        }
  }
  for (std::size_t i = 0; i < st.size(); ++i)
    if (mark[i]) st[i] = kUnknown;
}

void label(const std::vector<std::uint8_t>& st, const Grid& g, LabelArray& labels,
           std::vector<Segment>& segments, bool occupied26) {
  const std::size_t n = g.dims.count(), nx = g.dims.nx, ny = g.dims.ny, sz = nx * ny;
  labels.resize(n);
  std::uint32_t* parent = labels.data();
  for (std::size_t i = 0; i < n; ++i) {
    const auto u = static_cast<std::uint32_t>(i);
    const std::size_t x = i % nx, y = (i / nx) % ny, z = i / sz;
    parent[u] = u;
    if (x > 0 && st[i - 1] == st[i]) unite(parent, u, u - 1);
    if (y > 0 && st[i - nx] == st[i]) unite(parent, u, static_cast<std::uint32_t>(i - nx));
    if (z > 0 && st[i - sz] == st[i]) unite(parent, u, static_cast<std::uint32_t>(i - sz));
    if (occupied26 && st[i] == static_cast<std::uint8_t>(State::occupied))
      for (int dz = -1; dz <= 0; ++dz)  // the 13 neighbours that precede voxel i in scan order
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0))) continue;
            const long xx = long(x) + dx, yy = long(y) + dy, zz = long(z) + dz;
            if (xx < 0 || yy < 0 || zz < 0 || xx >= long(nx) || yy >= long(ny)) continue;
            const std::size_t j = std::size_t(xx) + nx * (std::size_t(yy) + ny * std::size_t(zz));
            if (st[j] == st[i]) unite(parent, u, static_cast<std::uint32_t>(j));
          }
  }
  segments.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const auto u = static_cast<std::uint32_t>(i);
    // parent[u] < u lies in u's set and already holds that set's id (find() would walk over
    // entries already rewritten to ids).
    const std::uint32_t r = parent[u];
    std::uint32_t id;
    if (r == u) {
      id = static_cast<std::uint32_t>(segments.size());
      Segment s;
      s.id = id;
      s.state = static_cast<State>(st[i]);
      s.bbox_min.fill(std::numeric_limits<std::uint32_t>::max());
      segments.push_back(s);
    } else {
      id = labels[r];
    }
    labels[i] = id;
  }
  // Mean occupancy: each run (a maximal stretch of one label along x) summed in eight lanes
  // (voxel k of the run into lane k % 8, lanes added as ((l0 + l1) + (l2 + l3)) + ((l4 + l5) +
  // (l6 + l7))), the runs added in scan order within each slab of kSlab z-planes, the slab
  // sums in slab order (the documented order of label_components()).
  std::vector<double> part(segments.size(), 0.0);
  for (std::size_t z = 0, i = 0; z < g.dims.nz; ++z) {
    if (z % kSlab == 0) std::fill(part.begin(), part.end(), 0.0);
    for (std::size_t y = 0; y < ny; ++y) {
      double lane[8] = {};
      std::size_t k = 0;  // position in the current run
      for (std::size_t x = 0; x < nx; ++x, ++i) {
        Segment& s = segments[labels[i]];
        ++s.voxels;
        lane[k % 8] += g.p[i];
        ++k;
        if (x + 1 == nx || labels[i + 1] != labels[i]) {  // the run ends here
          part[labels[i]] += ((lane[0] + lane[1]) + (lane[2] + lane[3])) + ((lane[4] + lane[5]) + (lane[6] + lane[7]));
          std::fill(lane, lane + 8, 0.0);
          k = 0;
        }
        const std::uint32_t c[3] = {static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                    static_cast<std::uint32_t>(z)};
        for (int a = 0; a < 3; ++a) {
          s.bbox_min[a] = std::min(s.bbox_min[a], c[a]);
          s.bbox_max[a] = std::max(s.bbox_max[a], c[a]);
          s.centroid[a] += c[a];
        }
      }
    }
    if (z % kSlab == kSlab - 1 || z + 1 == g.dims.nz)
      for (std::size_t k = 0; k < segments.size(); ++k) segments[k].mop += part[k];
  }
  for (auto& s : segments) {
    const double v = static_cast<double>(s.voxels);
    s.mop /= v;
    for (int a = 0; a < 3; ++a) s.centroid[a] /= v;
  }
}

void apply_surface_band(std::vector<std::uint8_t>& st, const Dims& d, const Params& params) {
  const int r = params.surface_band;
  if (r <= 0) return;
  const long nx = static_cast<long>(d.nx), ny = static_cast<long>(d.ny), nz = static_cast<long>(d.nz);
  const auto at = [&](long x, long y, long z) { return static_cast<std::size_t>(x + nx * (y + ny * z)); };
  const auto inside = [&](long x, long y, long z) { return x >= 0 && y >= 0 && z >= 0 && x < nx && y < ny && z < nz; };
  const auto free_or_out = [&](long x, long y, long z) { return !inside(x, y, z) || st[at(x, y, z)] == 0; };
  std::vector<std::size_t> band;
  for (long z = 0; z < nz; ++z)
    for (long y = 0; y < ny; ++y)
      for (long x = 0; x < nx; ++x) {
        if (st[at(x, y, z)] != 0) continue;
        bool thick = false;  // some cube centred in the map at (cx, cy, cz) = (x, y, z) + (-1..1) all free
        for (long cz = z - 1; cz <= z + 1 && !thick; ++cz)
          for (long cy = y - 1; cy <= y + 1 && !thick; ++cy)
            for (long cx = x - 1; cx <= x + 1 && !thick; ++cx) {
              if (!inside(cx, cy, cz)) continue;
              bool all = true;
              for (long k = 0; k < 27 && all; ++k) all = free_or_out(cx - 1 + k % 3, cy - 1 + (k / 3) % 3, cz - 1 + k / 9);
              thick = all;
            }
        if (thick) continue;
        bool occupied = false, unknown = false;
        for (long dz = -r; dz <= r; ++dz)
          for (long dy = -r; dy <= r; ++dy)
            for (long dx = -r; dx <= r; ++dx) {
              if (std::labs(dx) + std::labs(dy) + std::labs(dz) > r || !inside(x + dx, y + dy, z + dz)) continue;
              const std::uint8_t s = st[at(x + dx, y + dy, z + dz)];
              occupied |= s == 2;
              unknown |= s == 1;
            }
        if (occupied && unknown) band.push_back(at(x, y, z));
      }
  for (const std::size_t i : band) st[i] = 2;
}

Output segment(const Grid& grid, const Params& params) {
  Output o;
  const TextureMap tex = reference::texture(grid, params.contrast_bins);
  o.blocks = reference::divide(grid, tex, params);
  o.created = reference::create(grid, o.blocks, params);
  std::vector<std::uint8_t> st = o.created;
  reference::refine_unknown(st, grid, params);
  reference::refine_boundaries(st, grid, params);
  if (params.preset == Preset::default_preset) {
    reference::apply_voxel_rules(st, grid, params);
    reference::apply_surface_band(st, grid.dims, params);
  }
  o.refined = st;
  reference::label(st, grid, o.labels, o.segments, params.occupied_connectivity == 26);
  return o;
}

}  // namespace occseg::reference
