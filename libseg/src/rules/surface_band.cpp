// The surface band (rules/surface_band.hpp): thin free voxels near both an occupied and an unknown
// voxel become occupied. Bit masks of 64 voxels of a row per word (util/bit_rows.hpp), three of
// them, each pass over whole masks parallel over planes.
#include "rules/surface_band.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include "occseg/parallel.hpp"
#include "rules/voxel_rules.hpp"
#include "util/bit_rows.hpp"

namespace occseg {

namespace {

using detail::word_t;
using rules::kOccupied;

struct Layout {
  std::size_t nx, ny, nz, W, P;  // W words per row, P words per plane
  std::uint64_t tail;            // the bits of a row's last word that hold voxels
  explicit Layout(const Dims& d)
      : nx(d.nx), ny(d.ny), nz(d.nz), W((d.nx + 63) / 64), P(d.ny * ((d.nx + 63) / 64)),
        tail(d.nx % 64 ? (std::uint64_t(1) << (d.nx % 64)) - 1 : ~std::uint64_t(0)) {}
  std::size_t words() const { return P * nz; }
};

// Along x, radius 1, one row: erosion (AND; outside the map counts as 1) or dilation (OR;
// outside 0). The bits past nx stay 0.
template <bool Erode>
void x_row(const word_t* in, word_t* out, std::size_t W, std::uint64_t tail) {
  const std::uint64_t pad = Erode ? ~tail : 0, outside = Erode ? ~std::uint64_t(0) : 0;
  std::uint64_t prev = outside, cur = W == 1 ? in[0] | pad : in[0];
  for (std::size_t i = 0; i < W; ++i) {
    const std::uint64_t next = i + 1 < W ? (i + 2 == W ? in[i + 1] | pad : in[i + 1]) : outside;
    const std::uint64_t lt = (cur << 1) | (prev >> 63), rt = (cur >> 1) | (next << 63);
    const std::uint64_t v = Erode ? (cur & lt & rt) : (cur | lt | rt);
    out[i] = i + 1 == W ? v & tail : v;
    prev = cur;
    cur = next;
  }
}

// The planes [z0, z1) of one pass of the 3 x 3 x 3 box erosion or dilation along one axis (0: x,
// 1: y, 2: z), from `in` to `out` (apart). Neighbours outside the map are left out (erosion: 1,
// dilation: 0). The y and z passes run over whole planes: rows y - 1 and y + 1 are W words
// before and after, planes z - 1 and z + 1 are P words before and after.
template <bool Erode>
void box_axis(const Layout& L, const word_t* in, word_t* out, int axis, std::size_t z0, std::size_t z1) {
  // (Sizes in locals: a store through word_t, which may alias anything, would reload them.)
  const std::size_t W = L.W, P = L.P, ny = L.ny, nz = L.nz;
  const std::uint64_t tail = L.tail;
  for (std::size_t z = z0; z < z1; ++z) {
    const word_t* const a = in + z * P;
    word_t* const o = out + z * P;
    if (axis == 0) {
      for (std::size_t y = 0; y < ny; ++y) x_row<Erode>(a + y * W, o + y * W, W, tail);
      continue;
    }
    std::copy(a, a + P, o);
    const auto op = [](std::uint64_t x, std::uint64_t y) { return Erode ? x & y : x | y; };
    if (axis == 1) {  // rows y - 1 and y + 1, W words before and after within the plane
      for (std::size_t i = W; i < P; ++i) o[i] = op(o[i], a[i - W]);
      for (std::size_t i = 0; i + W < P; ++i) o[i] = op(o[i], a[i + W]);
    } else {  // planes z - 1 and z + 1, P words before and after
      if (z > 0) {
        const word_t* const below = a - P;  // (a[i - P] would wrap the unsigned index: UB)
        for (std::size_t i = 0; i < P; ++i) o[i] = op(o[i], below[i]);
      }
      if (z + 1 < nz)
        for (std::size_t i = 0; i < P; ++i) o[i] = op(o[i], a[i + P]);
    }
  }
}

// The planes [z0, z1) of out = the voxels of `in` and their 6 face neighbours (one face step).
void face_dilate(const Layout& L, const word_t* in, word_t* out, std::size_t z0, std::size_t z1) {
  const std::size_t W = L.W, P = L.P, ny = L.ny, nz = L.nz;
  const std::uint64_t tail = L.tail;
  for (std::size_t z = z0; z < z1; ++z) {
    const word_t* const a = in + z * P;
    word_t* const o = out + z * P;
    for (std::size_t y = 0; y < ny; ++y) x_row<false>(a + y * W, o + y * W, W, tail);
    for (std::size_t i = W; i < P; ++i) o[i] |= a[i - W];
    for (std::size_t i = 0; i + W < P; ++i) o[i] |= a[i + W];
    if (z > 0)
      for (std::size_t i = 0; i < P; ++i) o[i] |= (a - P)[i];
    if (z + 1 < nz)
      for (std::size_t i = 0; i < P; ++i) o[i] |= a[i + P];
  }
}

// Runs fn(z0, z1) over the planes on the threads; every pass waits for the one before.
template <typename Fn>
void planes(const Layout& L, int threads, Fn&& fn) {
  parallel_for(L.nz, threads, [&](std::size_t z0, std::size_t z1) { fn(z0, z1); });
}

}  // namespace

std::size_t surface_band_scratch_bytes(const Dims& dims) { return 4 * Layout(dims).words() * sizeof(std::uint64_t); }

void apply_surface_band(std::uint8_t* st, const Dims& dims, const Params& params, std::uint8_t* scratch,
                        std::size_t scratch_bytes, std::vector<std::uint64_t>* added, const kernels::Table& k) {
  if (added) added->clear();
  const int r = params.surface_band;
  if (r <= 0 || dims.count() == 0) return;
  const Layout L(dims);
  const std::size_t n = L.words();
  std::vector<std::uint64_t> own;
  word_t* base;
  if (scratch && surface_band_scratch_bytes(dims) <= scratch_bytes) {
    base = reinterpret_cast<word_t*>(scratch);
  } else {
    own.resize(4 * n);
    base = reinterpret_cast<word_t*>(own.data());
  }
  word_t *const c = base, *u = base + n, *a = base + 2 * n, *b = base + 3 * n;
  const int t = params.threads;
  // c: the free voxels, u: the unknown ones, row by row.
  planes(L, t, [&](std::size_t z0, std::size_t z1) {
    const std::size_t nx = L.nx, W = L.W;
    for (std::size_t row = z0 * L.ny, e = z1 * L.ny; row < e; ++row)
      k.refine.pack_states(st + row * nx, nx, u + row * W, c + row * W);
  });
  // The thin free voxels: c without the opening of c by the 3 x 3 x 3 cube (into b).
  planes(L, t, [&](std::size_t z0, std::size_t z1) { box_axis<true>(L, c, a, 0, z0, z1); });
  planes(L, t, [&](std::size_t z0, std::size_t z1) { box_axis<true>(L, a, b, 1, z0, z1); });
  planes(L, t, [&](std::size_t z0, std::size_t z1) { box_axis<true>(L, b, a, 2, z0, z1); });
  planes(L, t, [&](std::size_t z0, std::size_t z1) { box_axis<false>(L, a, b, 0, z0, z1); });
  planes(L, t, [&](std::size_t z0, std::size_t z1) { box_axis<false>(L, b, a, 1, z0, z1); });
  planes(L, t, [&](std::size_t z0, std::size_t z1) {
    box_axis<false>(L, a, b, 2, z0, z1);  // b: the opening
    for (std::size_t i = z0 * L.P, e = z1 * L.P; i < e; ++i) c[i] &= ~b[i];
  });
  // Within r face steps of an unknown voxel (u, then a, b in turn), then of an occupied one. The
  // states are still as they came in: there is no cascade.
  const auto near = [&](word_t* m, word_t* other) {
    for (int step = 0; step < r; ++step) {
      planes(L, t, [&](std::size_t z0, std::size_t z1) { face_dilate(L, m, other, z0, z1); });
      std::swap(m, other);
    }
    planes(L, t, [&](std::size_t z0, std::size_t z1) {
      for (std::size_t i = z0 * L.P, e = z1 * L.P; i < e; ++i) c[i] &= m[i];
    });
  };
  near(u, a);
  planes(L, t, [&](std::size_t z0, std::size_t z1) {
    const std::size_t nx = L.nx, W = L.W;
    for (std::size_t row = z0 * L.ny, e = z1 * L.ny; row < e; ++row)
      k.refine.pack_equal(st + row * nx, nx, kOccupied, a + row * W);
  });
  near(a, b);
  if (added) added->assign(c, c + n);
  planes(L, t, [&](std::size_t z0, std::size_t z1) {
    const std::size_t nx = L.nx, W = L.W;
    for (std::size_t row = z0 * L.ny, e = z1 * L.ny; row < e; ++row) {
      std::uint8_t* const s = st + row * nx;
      for (std::size_t w = 0; w < W; ++w)
        for (std::uint64_t bits = c[row * W + w]; bits; bits &= bits - 1)
          s[w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits))] = kOccupied;
    }
  });
}

std::vector<std::uint64_t> surface_band_voxels(const std::vector<std::uint64_t>& added, const Dims& dims,
                                               const std::uint32_t* labels, std::size_t segments) {
  std::vector<std::uint64_t> count(segments, 0);
  if (added.empty()) return count;
  const Layout L(dims);
  for (std::size_t row = 0; row < dims.ny * dims.nz; ++row)
    for (std::size_t w = 0; w < L.W; ++w)
      for (std::uint64_t bits = added[row * L.W + w]; bits; bits &= bits - 1)
        ++count[labels[row * L.nx + w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits))]];
  return count;
}

}  // namespace occseg
