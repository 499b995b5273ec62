// The surface band (rules/surface_band.hpp): thin free voxels near both an occupied and an unknown
// voxel become occupied. Bit masks of 64 voxels of a row per word (util/bit_rows.hpp), three of
// them, each pass over whole masks parallel over planes.
#include "rules/surface_band.hpp"

#include <vector>

#include "occseg/parallel.hpp"
#include "rules/voxel_rules.hpp"
#include "util/bit_rows.hpp"

namespace occseg {

namespace {

using detail::word_t;
using rules::kFree;
using rules::kOccupied;
using rules::kUnknown;

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

// One pass of the 3 x 3 x 3 box erosion or dilation along one axis (0: x, 1: y, 2: z), from `in`
// to `out` (apart). Neighbours outside the map are left out (erosion: 1, dilation: 0).
template <bool Erode>
void box_axis(const Layout& L, const word_t* in, word_t* out, int axis, int threads) {
  parallel_for(L.nz, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < L.ny; ++y) {
        const std::size_t at = z * L.P + y * L.W;
        if (axis == 0) {
          x_row<Erode>(in + at, out + at, L.W, L.tail);
          continue;
        }
        const std::size_t step = axis == 1 ? L.W : L.P;
        const bool lo = axis == 1 ? y > 0 : z > 0, hi = axis == 1 ? y + 1 < L.ny : z + 1 < L.nz;
        for (std::size_t i = 0; i < L.W; ++i) {
          std::uint64_t v = in[at + i];
          if (lo) v = Erode ? v & in[at + i - step] : v | in[at + i - step];
          if (hi) v = Erode ? v & in[at + i + step] : v | in[at + i + step];
          out[at + i] = v;
        }
      }
  });
}

// out = the voxels of `in` and their 6 face neighbours (one face step of dilation).
void face_dilate(const Layout& L, const word_t* in, word_t* out, int threads) {
  parallel_for(L.nz, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < L.ny; ++y) {
        const std::size_t at = z * L.P + y * L.W;
        x_row<false>(in + at, out + at, L.W, L.tail);
        for (std::size_t i = 0; i < L.W; ++i) {
          std::uint64_t v = out[at + i];
          if (y > 0) v |= in[at + i - L.W];
          if (y + 1 < L.ny) v |= in[at + i + L.W];
          if (z > 0) v |= in[at + i - L.P];
          if (z + 1 < L.nz) v |= in[at + i + L.P];
          out[at + i] = v;
        }
      }
  });
}

void pack(const Layout& L, const std::uint8_t* st, std::uint8_t v, word_t* out, int threads) {
  parallel_for(L.nz, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t r = z0 * L.ny; r < z1 * L.ny; ++r) detail::pack_equal(st + r * L.nx, L.nx, v, out + r * L.W);
  });
}

// The voxels of state v within r face steps, into `a` (with `b` as the other buffer of the
// ping-pong); returns the buffer that holds them.
word_t* within(const Layout& L, const std::uint8_t* st, std::uint8_t v, int r, word_t* a, word_t* b, int threads) {
  pack(L, st, v, a, threads);
  for (int k = 0; k < r; ++k) {
    face_dilate(L, a, b, threads);
    std::swap(a, b);
  }
  return a;
}

}  // namespace

std::size_t surface_band_scratch_bytes(const Dims& dims) { return 3 * Layout(dims).words() * sizeof(std::uint64_t); }

void apply_surface_band(std::uint8_t* st, const Dims& dims, const Params& params, std::uint8_t* scratch,
                        std::size_t scratch_bytes, std::vector<std::uint64_t>* added) {
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
    own.resize(3 * n);
    base = reinterpret_cast<word_t*>(own.data());
  }
  word_t *const c = base, *a = base + n, *b = base + 2 * n;
  const int t = params.threads;
  // The thin free voxels: free and not in the opening of the free voxels by the 3 x 3 x 3 cube.
  pack(L, st, kFree, c, t);
  box_axis<true>(L, c, a, 0, t);
  box_axis<true>(L, a, b, 1, t);
  box_axis<true>(L, b, a, 2, t);
  box_axis<false>(L, a, b, 0, t);
  box_axis<false>(L, b, a, 1, t);
  box_axis<false>(L, a, b, 2, t);  // b: the opening
  parallel_for(L.nz, t, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t i = z0 * L.P; i < z1 * L.P; ++i) c[i] &= ~b[i];
  });
  // Near an occupied voxel, then near an unknown one (the states are still as they came in).
  const std::uint8_t near_states[2] = {kOccupied, kUnknown};
  for (const std::uint8_t v : near_states) {
    const word_t* const m = within(L, st, v, r, a, b, t);
    parallel_for(L.nz, t, [&](std::size_t z0, std::size_t z1) {
      for (std::size_t i = z0 * L.P; i < z1 * L.P; ++i) c[i] &= m[i];
    });
  }
  if (added) added->assign(c, c + n);
  parallel_for(L.nz, t, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t row = z0 * L.ny; row < z1 * L.ny; ++row) {
      std::uint8_t* const s = st + row * L.nx;
      for (std::size_t w = 0; w < L.W; ++w)
        for (std::uint64_t bits = c[row * L.W + w]; bits; bits &= bits - 1)
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
