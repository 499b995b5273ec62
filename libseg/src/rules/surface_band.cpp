// The surface band (rules/surface_band.hpp): thin free voxels near both an occupied and an unknown
// voxel become occupied. Bit rows of 64 voxels per word (util/bit_rows.hpp), worked on row by row
// and only where the result can be non-empty: most of a map is thick free space or unknown far
// from any occupied voxel, and its rows are never read.
//
// With F, U, O the rows of free, unknown and occupied voxels, the result is
//   F & D(U) & D(O) & ~open(F),
// D the voxels within r face steps (the L1 ball of radius r, clipped by the map: a box is convex,
// so the ball within it is what r face dilations give), open(F) the opening of F by the 3 x 3 x 3
// cube (erosion with the outside free, dilation with the outside empty). Both are computed per
// row of voxels (y, z), and only on the rows where they are needed:
//  - D: r rounds of one face step (x +- 1 within the row, the rows y +- 1 and z +- 1), round j on
//    the rows within r - j steps (in y and z) of a row whose result is wanted;
//  - the erosion and the dilation by a cube are both separable and commute with OR (AND) over
//    rows, so erode(F) of row q = x-erosion of the AND of F's 3 x 3 rows around q (in the map),
//    and open(F) of row q = x-dilation of the OR of erode(F)'s 3 x 3 rows around q.
// The passes: (1) the rows with a free voxel and occupied and unknown ones within r steps (row
// flags): M = F & D(O), then M &= D(U) where M is not empty; (2) erode(F) for the rows around the
// rows M kept; (3) the result on those. Each pass is parallel over planes and writes only its own
// rows: the result never depends on the thread count.
#include "rules/surface_band.hpp"

#include <algorithm>
#include <vector>

#include "occseg/parallel.hpp"
#include "rules/voxel_rules.hpp"
#include "util/bit_rows.hpp"

namespace occseg {

namespace {

using detail::StateBits;
using detail::word_t;
using rules::kOccupied;

struct Layout {
  std::size_t nx, ny, nz, W, P;  // W words per row, P words per plane
  std::uint64_t tail;            // the bits of a row's last word that hold voxels
  explicit Layout(const Dims& d)
      : nx(d.nx), ny(d.ny), nz(d.nz), W((d.nx + 63) / 64), P(d.ny * ((d.nx + 63) / 64)),
        tail(d.nx % 64 ? (std::uint64_t(1) << (d.nx % 64)) - 1 : ~std::uint64_t(0)) {}
  std::size_t rows() const { return ny * nz; }
  std::size_t words() const { return P * nz; }
};

// acc |= the x-dilation of row `in` by k (1 <= k < 64) face steps along x, clipped by the row.
void or_x_dilated(std::uint64_t* acc, const std::uint64_t* in, std::size_t W, std::uint64_t tail, unsigned k) {
  std::uint64_t prev = 0, cur = in[0];
  for (std::size_t i = 0; i < W; ++i) {
    const std::uint64_t next = i + 1 < W ? in[i + 1] : 0;
    std::uint64_t v = cur;
    for (unsigned s = 1; s <= k; ++s) v |= (cur << s) | (prev >> (64 - s)) | (cur >> s) | (next << (64 - s));
    acc[i] |= i + 1 == W ? v & tail : v;
    prev = cur;
    cur = next;
  }
}

// out = the x-erosion of row `in` by one step (the outside, and the bits past nx, count as set;
// the bits past nx of out are 0).
void x_eroded(const std::uint64_t* in, word_t* out, std::size_t W, std::uint64_t tail) {
  const std::uint64_t pad = ~tail, all = ~std::uint64_t(0);
  std::uint64_t prev = all, cur = W == 1 ? in[0] | pad : in[0];
  for (std::size_t i = 0; i < W; ++i) {
    const std::uint64_t next = i + 1 < W ? (i + 2 == W ? in[i + 1] | pad : in[i + 1]) : all;
    const std::uint64_t v = cur & ((cur << 1) | (prev >> 63)) & ((cur >> 1) | (next << 63));
    out[i] = i + 1 == W ? v & tail : v;
    prev = cur;
    cur = next;
  }
}

// Rows [y0, y1) of plane z of one face step of `in` (the voxels and their 6 face neighbours,
// within the map) into `out`: along x row by row, then the rows y +- 1 and planes z +- 1 as flat
// loops over the run's words.
inline void face_step_rows(const Layout& L, const word_t* in, word_t* out, std::size_t y0, std::size_t y1,
                           std::size_t z) {
  const std::size_t W = L.W, P = L.P, ny = L.ny;
  const std::uint64_t tail = L.tail;
  for (std::size_t y = y0; y < y1; ++y) {
    const word_t* const c = in + (y + ny * z) * W;
    word_t* const o = out + (y + ny * z) * W;
    for (std::size_t i = 0; i < W; ++i) {
      const std::uint64_t prev = i > 0 ? c[i - 1] : 0, next = i + 1 < W ? c[i + 1] : 0;
      const std::uint64_t v = c[i] | (c[i] << 1) | (prev >> 63) | (c[i] >> 1) | (next << 63);
      o[i] = i + 1 == W ? v & tail : v;
    }
  }
  const std::size_t b = (y0 + ny * z) * W, e = (y1 + ny * z) * W;  // the run's words
  word_t* const o = out;
  // y - 1 (rows y0 > 0 or later) and y + 1 (rows up to ny - 2)
  for (std::size_t i = std::max(b, (ny * z + 1) * W); i < e; ++i) o[i] |= in[i - W];
  for (std::size_t i = b, ee = std::min(e, (ny * z + ny - 1) * W); i < ee; ++i) o[i] |= in[i + W];
  if (z > 0) {
    const word_t* const below = in + b - P;  // (in[i - P] would wrap the unsigned index at z = 0)
    for (std::size_t i = 0; i < e - b; ++i) o[b + i] |= below[i];
  }
  if (z + 1 < L.nz)
    for (std::size_t i = b; i < e; ++i) o[i] |= in[i + P];
}

std::vector<std::uint8_t> kinds_within(const Layout& L, const std::uint8_t* kinds, int r);

// D(src) (r face steps) on the rows flagged in `want`, in a or b (the one returned): r rounds of
// one face step, round j on the rows within r - j steps (in y and z) of a wanted row, which are
// all round j + 1 reads. Other rows of a and b are left as they were.
const word_t* reach_rows(const Layout& L, const word_t* src, const std::vector<std::uint8_t>& want, int r, word_t* a,
                         word_t* b, int threads) {
  std::vector<std::vector<std::uint8_t>> need(static_cast<std::size_t>(r) + 1);
  need[static_cast<std::size_t>(r)] = want;
  for (int j = r - 1; j >= 1; --j)
    need[static_cast<std::size_t>(j)] = kinds_within(L, need[static_cast<std::size_t>(j) + 1].data(), 1);
  const word_t* in = src;
  for (int j = 1; j <= r; ++j) {
    word_t* const out = j % 2 ? a : b;
    const std::uint8_t* const flags = need[static_cast<std::size_t>(j)].data();
    parallel_for(L.nz, threads, [&](std::size_t z0, std::size_t z1) {
      for (std::size_t z = z0; z < z1; ++z)
        for (std::size_t y = 0; y < L.ny;) {  // runs of flagged rows
          if (!flags[y + L.ny * z]) {
            ++y;
            continue;
          }
          std::size_t y1 = y + 1;
          while (y1 < L.ny && flags[y1 + L.ny * z]) ++y1;
          face_step_rows(L, in, out, y, y1, z);
          y = y1;
        }
    });
    in = out;
  }
  return in;
}

// out = in OR-ed with its neighbours along y (one plane's row flags, ny of them).
void or_y_neighbours(const std::uint8_t* in, std::uint8_t* out, std::size_t ny) {
  std::copy(in, in + ny, out);
  for (std::size_t y = 1; y < ny; ++y) out[y] |= in[y - 1];
  for (std::size_t y = 0; y + 1 < ny; ++y) out[y] |= in[y + 1];
}

// The row kinds of every row within L1 distance r (in y and z) of it, OR-ed: r rounds of the
// four neighbours within the map.
std::vector<std::uint8_t> kinds_within(const Layout& L, const std::uint8_t* kinds, int r) {
  const std::size_t ny = L.ny, nz = L.nz;
  std::vector<std::uint8_t> a(kinds, kinds + L.rows()), b(L.rows());
  for (int step = 0; step < r; ++step) {
    for (std::size_t z = 0; z < nz; ++z) {
      const std::uint8_t* const in = a.data() + z * ny;
      std::uint8_t* const out = b.data() + z * ny;
      or_y_neighbours(in, out, ny);
      if (z > 0) {
        const std::uint8_t* const below = in - ny;  // (in[y - ny] would wrap the unsigned index)
        for (std::size_t y = 0; y < ny; ++y) out[y] |= below[y];
      }
      if (z + 1 < nz)
        for (std::size_t y = 0; y < ny; ++y) out[y] |= in[y + ny];
    }
    std::swap(a, b);
  }
  return a;
}

// The rows within one step in y and in z (diagonals too) of a flagged row: the flags dilated along
// y, then along z.
std::vector<std::uint8_t> rows_around(const Layout& L, const std::vector<std::uint8_t>& flags) {
  const std::size_t ny = L.ny, nz = L.nz;
  std::vector<std::uint8_t> a(L.rows()), b(L.rows());
  for (std::size_t z = 0; z < nz; ++z) {
    const std::uint8_t* const in = flags.data() + z * ny;
    std::uint8_t* const out = a.data() + z * ny;
    or_y_neighbours(in, out, ny);
  }
  for (std::size_t z = 0; z < nz; ++z) {
    const std::uint8_t* const in = a.data() + z * ny;
    std::uint8_t* const out = b.data() + z * ny;
    std::copy(in, in + ny, out);
    if (z > 0) {
      const std::uint8_t* const below = in - ny;
      for (std::size_t y = 0; y < ny; ++y) out[y] |= below[y];
    }
    if (z + 1 < nz)
      for (std::size_t y = 0; y < ny; ++y) out[y] |= in[y + ny];
  }
  return b;
}

}  // namespace

std::size_t detail::surface_band_rows_scratch_bytes(const Dims& dims) {
  return 4 * Layout(dims).words() * sizeof(std::uint64_t);
}

std::size_t surface_band_scratch_bytes(const Dims& dims) {
  return 3 * Layout(dims).words() * sizeof(std::uint64_t) + detail::surface_band_rows_scratch_bytes(dims);
}

void detail::apply_surface_band(std::uint8_t* st, const StateBits& bits, const Dims& dims, const Params& params,
                                std::uint8_t* scratch, std::size_t scratch_bytes, std::vector<std::uint64_t>* added) {
  if (added) added->clear();
  const int r = params.surface_band;
  if (r <= 0 || dims.count() == 0) return;
  const Layout L(dims);
  const std::size_t n = L.words(), rows = L.rows(), W = L.W, ny = L.ny, nz = L.nz;
  std::vector<std::uint64_t> own;
  word_t* base;
  if (scratch && surface_band_rows_scratch_bytes(dims) <= scratch_bytes) {
    base = reinterpret_cast<word_t*>(scratch);
  } else {
    own.resize(4 * n);
    base = reinterpret_cast<word_t*>(own.data());
  }
  // m: M of the rows flagged in `kept`, e: erode(F) of the rows flagged in `eroded`; the other
  // rows of both are never read, so neither is cleared. The result goes into `added` (cleared: it
  // is read whole) or over m.
  word_t* const m = base;
  word_t* const e = base + n;
  word_t* const da = base + 2 * n;  // D(O), then D(U): the rounds of the face steps
  word_t* const db = base + 3 * n;
  word_t* res = m;
  if (added) {
    added->assign(n, 0);
    res = reinterpret_cast<word_t*>(added->data());
  }
  const std::uint8_t* const kinds = bits.rows;
  // Which rows may keep a voxel: a free voxel, and occupied and unknown ones within reach.
  const std::vector<std::uint8_t> near = kinds_within(L, kinds, r);
  std::vector<std::uint8_t> kept(rows, 0), plane_kept(nz, 0);
  // (1) M = F & D(O) & D(U) on those rows (D(U) only where F & D(O) holds a voxel).
  std::vector<std::uint8_t> want(rows, 0);
  constexpr std::uint8_t both = StateBits::kOccupied | StateBits::kUnknown;
  for (std::size_t q = 0; q < rows; ++q) want[q] = (kinds[q] & StateBits::kFree) && (near[q] & both) == both;
  const word_t* const d_occupied = reach_rows(L, bits.occupied, want, r, da, db, params.threads);
  parallel_for(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t q = z0 * ny; q < z1 * ny; ++q) {
      if (!want[q]) continue;
      std::uint64_t any = 0;
      for (std::size_t i = 0; i < W; ++i) any |= m[q * W + i] = bits.free[q * W + i] & d_occupied[q * W + i];
      want[q] = any != 0;
    }
  });
  const word_t* const d_unknown = reach_rows(L, bits.unknown, want, r, da, db, params.threads);
  parallel_for(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z) {
      std::uint8_t any_kept = 0;
      for (std::size_t q = z * ny; q < (z + 1) * ny; ++q) {
        if (!want[q]) continue;
        std::uint64_t any = 0;
        for (std::size_t i = 0; i < W; ++i) any |= m[q * W + i] &= d_unknown[q * W + i];
        kept[q] = any != 0;
        any_kept |= kept[q];
      }
      plane_kept[z] = any_kept;
    }
  });
  // (2) erode(F) of the rows within one step (in y and z, diagonals too) of a kept row.
  const std::vector<std::uint8_t> around = rows_around(L, kept);
  parallel_for(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::uint64_t> all(W);
    for (std::size_t z = z0; z < z1; ++z) {
      const std::size_t za = z > 0 ? z - 1 : 0, zb = std::min(nz - 1, z + 1);
      for (std::size_t y = 0; y < ny; ++y) {
        if (!around[y + ny * z]) continue;
        const std::size_t ya = y > 0 ? y - 1 : 0, yb = std::min(ny - 1, y + 1);
        // The AND of F's rows around (y, z) in the map (outside: free), then along x.
        std::fill(all.begin(), all.end(), ~std::uint64_t(0));
        for (std::size_t zz = za; zz <= zb; ++zz)
          for (std::size_t yy = ya; yy <= yb; ++yy) {
            const word_t* const f = bits.free + (yy + ny * zz) * W;
            for (std::size_t i = 0; i < W; ++i) all[i] &= f[i];
          }
        x_eroded(all.data(), e + (y + ny * z) * W, W, L.tail);
      }
    }
  });
  // (3) The result on the kept rows: M without open(F); the states written.
  parallel_for(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::uint64_t> any(W), open(W);
    for (std::size_t z = z0; z < z1; ++z) {
      if (!plane_kept[z]) continue;
      const std::size_t za = z > 0 ? z - 1 : 0, zb = std::min(nz - 1, z + 1);
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t q = y + ny * z;
        if (!kept[q]) continue;
        const std::size_t ya = y > 0 ? y - 1 : 0, yb = std::min(ny - 1, y + 1);
        std::fill(any.begin(), any.end(), 0);
        for (std::size_t zz = za; zz <= zb; ++zz)
          for (std::size_t yy = ya; yy <= yb; ++yy) {
            const word_t* const er = e + (yy + ny * zz) * W;  // (eroded: every row around a kept one)
            for (std::size_t i = 0; i < W; ++i) any[i] |= er[i];
          }
        std::fill(open.begin(), open.end(), 0);
        or_x_dilated(open.data(), any.data(), W, L.tail, 1);
        std::uint8_t* const s = st + q * L.nx;
        for (std::size_t w = 0; w < W; ++w) {
          const std::uint64_t v = m[q * W + w] & ~open[w];
          res[q * W + w] = v;
          for (std::uint64_t b = v; b; b &= b - 1) s[w * 64 + static_cast<std::size_t>(__builtin_ctzll(b))] = kOccupied;
        }
      }
    }
  });
}

void detail::state_bits(const std::uint8_t* st, const Dims& dims, int threads, std::uint64_t* storage,
                        std::uint8_t* rows, StateBits& out, const kernels::Table& k) {
  const Layout L(dims);
  const std::size_t n = L.words(), W = L.W, nx = L.nx;
  word_t* const f = reinterpret_cast<word_t*>(storage);
  word_t* const u = f + n;
  word_t* const o = f + 2 * n;
  parallel_for(L.nz, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t q = z0 * L.ny, e = z1 * L.ny; q < e; ++q) {
      k.refine.pack_states(st + q * nx, nx, u + q * W, f + q * W);
      k.refine.pack_equal(st + q * nx, nx, kOccupied, o + q * W);
      rows[q] = detail::row_kinds(f + q * W, u + q * W, o + q * W, W);
    }
  });
  out.free = f;
  out.unknown = u;
  out.occupied = o;
  out.words = W;
  out.rows = rows;
}

void apply_surface_band(std::uint8_t* st, const Dims& dims, const Params& params, std::uint8_t* scratch,
                        std::size_t scratch_bytes, std::vector<std::uint64_t>* added, const kernels::Table& k) {
  if (added) added->clear();
  if (params.surface_band <= 0 || dims.count() == 0) return;
  const Layout L(dims);
  const std::size_t n = L.words();
  std::vector<std::uint64_t> own;
  std::uint64_t* base;
  if (scratch && surface_band_scratch_bytes(dims) <= scratch_bytes) {
    base = reinterpret_cast<std::uint64_t*>(scratch);
  } else {
    own.resize(surface_band_scratch_bytes(dims) / sizeof(std::uint64_t));
    base = own.data();
  }
  std::vector<std::uint8_t> rows(L.rows());
  detail::StateBits bits;
  detail::state_bits(st, dims, params.threads, base, rows.data(), bits, k);
  detail::apply_surface_band(st, bits, dims, params, reinterpret_cast<std::uint8_t*>(base + 3 * n),
                             detail::surface_band_rows_scratch_bytes(dims), added);
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
