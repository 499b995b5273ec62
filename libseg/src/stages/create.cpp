#include "stages/create.hpp"

#include <algorithm>
#include <cstring>
#include <optional>
#include <utility>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include "occseg/parallel.hpp"
#include "stages/texture.hpp"
#include "kernels/cpu_features.hpp"
#include "util/huge_pages.hpp"
#include "util/bit_rows.hpp"
#include "stages/own_states.hpp"

namespace occseg {

using detail::pack_equal;
using detail::word_t;
#if defined(__x86_64__) && defined(__GNUC__)
using detail::pack_equal_avx2;
#endif

double mean_occupancy(const Grid& grid, const Block& b) {
  // Cell by cell (kMeanCell^3 cells anchored at voxel 0), each cell's part in scan order.
  constexpr std::uint32_t k = kMeanCell;
  double sum = 0;
  for (std::uint32_t cz = b.lo[2] / k * k; cz < b.hi[2]; cz += k)
    for (std::uint32_t cy = b.lo[1] / k * k; cy < b.hi[1]; cy += k)
      for (std::uint32_t cx = b.lo[0] / k * k; cx < b.hi[0]; cx += k) {
        double part = 0;
        for (std::uint32_t z = std::max(cz, b.lo[2]); z < std::min(cz + k, b.hi[2]); ++z)
          for (std::uint32_t y = std::max(cy, b.lo[1]); y < std::min(cy + k, b.hi[1]); ++y) {
            const float* row = grid.p.data() + grid.index(0, y, z);
            for (std::uint32_t x = std::max(cx, b.lo[0]); x < std::min(cx + k, b.hi[0]); ++x) part += row[x];
          }
        sum += part;
      }
  return sum / static_cast<double>(b.volume());
}

namespace {

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_CREATE_AVX2 1
// sums[k] += v[8k] + ... + v[8k + 7] for the first `cells` cells of a row (a multiple of 8
// of them), each sum's additions in the scalar loop's order (acc += v[0], then v[1], ...): eight
// cells at a time, their 8 x 8 floats transposed so that lane k holds cell k, then converted and
// added in double, four lanes per register. The same additions as the scalar loop, so the same
// sums; a third of its instructions (with the states no longer zeroed, creation 7.5 -> 5.5 ms on
// two threads; docs/performance.md, "Sixth round").
__attribute__((target("avx2"))) void add_cells_avx2(const float* v, double* sums, std::size_t cells) {
  for (std::size_t k = 0; k + 8 <= cells; k += 8, v += 64) {
    __m256 r[8];
    for (int j = 0; j < 8; ++j) r[j] = _mm256_loadu_ps(v + 8 * j);  // r[j][i] = cell j, voxel i
    // 8 x 8 transpose: t[i][j] = r[j][i].
    const __m256 a0 = _mm256_unpacklo_ps(r[0], r[1]), a1 = _mm256_unpackhi_ps(r[0], r[1]);
    const __m256 a2 = _mm256_unpacklo_ps(r[2], r[3]), a3 = _mm256_unpackhi_ps(r[2], r[3]);
    const __m256 a4 = _mm256_unpacklo_ps(r[4], r[5]), a5 = _mm256_unpackhi_ps(r[4], r[5]);
    const __m256 a6 = _mm256_unpacklo_ps(r[6], r[7]), a7 = _mm256_unpackhi_ps(r[6], r[7]);
    const __m256 b0 = _mm256_shuffle_ps(a0, a2, 0x44), b1 = _mm256_shuffle_ps(a0, a2, 0xEE);
    const __m256 b2 = _mm256_shuffle_ps(a1, a3, 0x44), b3 = _mm256_shuffle_ps(a1, a3, 0xEE);
    const __m256 b4 = _mm256_shuffle_ps(a4, a6, 0x44), b5 = _mm256_shuffle_ps(a4, a6, 0xEE);
    const __m256 b6 = _mm256_shuffle_ps(a5, a7, 0x44), b7 = _mm256_shuffle_ps(a5, a7, 0xEE);
    const __m256 t[8] = {_mm256_permute2f128_ps(b0, b4, 0x20), _mm256_permute2f128_ps(b1, b5, 0x20),
                         _mm256_permute2f128_ps(b2, b6, 0x20), _mm256_permute2f128_ps(b3, b7, 0x20),
                         _mm256_permute2f128_ps(b0, b4, 0x31), _mm256_permute2f128_ps(b1, b5, 0x31),
                         _mm256_permute2f128_ps(b2, b6, 0x31), _mm256_permute2f128_ps(b3, b7, 0x31)};
    __m256d lo = _mm256_loadu_pd(sums + k), hi = _mm256_loadu_pd(sums + k + 4);
    for (int i = 0; i < 8; ++i) {
      lo = _mm256_add_pd(lo, _mm256_cvtps_pd(_mm256_castps256_ps128(t[i])));
      hi = _mm256_add_pd(hi, _mm256_cvtps_pd(_mm256_extractf128_ps(t[i], 1)));
    }
    _mm256_storeu_pd(sums + k, lo);
    _mm256_storeu_pd(sums + k + 4, hi);
  }
}

// add_cells_avx2 in AVX-512 (F only): the eight cells' sums in one register of eight doubles,
// and each pair of additions' floats (voxels i and i + 1 of the eight cells) picked out of the
// 64 loaded floats by two two-register permutes and a blend instead of the 8 x 8 transpose: 38
// instead of 68 instructions per eight cells, the same additions in the same order. (GCC 12 warns
// inside its own AVX-512 intrinsics, whose pass-through operands are deliberately undefined.)
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
__attribute__((target("avx512f"))) void add_cells_avx512(const float* v, double* sums, std::size_t cells) {
  __m512i ia[4], ib[4];  // pair q: voxels 2q (lanes 0-7) and 2q + 1 (lanes 8-15)
  for (int q = 0; q < 4; ++q) {
    alignas(64) std::int32_t a[16] = {}, b[16] = {};
    for (int j = 0; j < 4; ++j) {
      a[j] = 8 * j + 2 * q;          // cell j (of registers 0-1): lanes 0-3
      a[8 + j] = 8 * j + 2 * q + 1;  // lanes 8-11
      b[4 + j] = 8 * j + 2 * q;      // cell 4 + j (of registers 2-3): lanes 4-7
      b[12 + j] = 8 * j + 2 * q + 1;  // lanes 12-15
    }
    ia[q] = _mm512_load_si512(a);
    ib[q] = _mm512_load_si512(b);
  }
  for (std::size_t k = 0; k + 8 <= cells; k += 8, v += 64) {
    const __m512 z0 = _mm512_loadu_ps(v), z1 = _mm512_loadu_ps(v + 16);  // cells 0-1, 2-3
    const __m512 z2 = _mm512_loadu_ps(v + 32), z3 = _mm512_loadu_ps(v + 48);  // cells 4-5, 6-7
    __m512d acc = _mm512_loadu_pd(sums + k);
    for (int q = 0; q < 4; ++q) {
      const __m512 w = _mm512_mask_blend_ps(0xF0F0, _mm512_permutex2var_ps(z0, ia[q], z1),
                                            _mm512_permutex2var_ps(z2, ib[q], z3));
      acc = _mm512_add_pd(acc, _mm512_cvtps_pd(_mm512_castps512_ps256(w)));
      acc = _mm512_add_pd(acc, _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(w), 1))));
    }
    _mm512_storeu_pd(sums + k, acc);
  }
}
#pragma GCC diagnostic pop

// detail::own_states_of() for 32 voxels per step (the scalar one takes the rest).
__attribute__((target("avx2"))) void own_states_avx2(const float* p, std::size_t n, float lo, float hi,
                                                     std::uint8_t* out) {
  const __m256 l = _mm256_set1_ps(lo), h = _mm256_set1_ps(hi);
  const __m256i one = _mm256_set1_epi32(1), order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    __m256i s[4];
    for (int j = 0; j < 4; ++j) {  // 1 + (p < lo ? -1 : 0) - (p > hi ? -1 : 0)
      const __m256 a = _mm256_loadu_ps(p + i + 8 * j);
      s[j] = _mm256_sub_epi32(_mm256_add_epi32(one, _mm256_castps_si256(_mm256_cmp_ps(a, l, _CMP_LT_OQ))),
                              _mm256_castps_si256(_mm256_cmp_ps(a, h, _CMP_GT_OQ)));
    }
    // The packs work within 128-bit halves: dwords come out as (0-3 of each s) (4-7 of each s).
    const __m256i bytes = _mm256_packs_epi16(_mm256_packs_epi32(s[0], s[1]), _mm256_packs_epi32(s[2], s[3]));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + i), _mm256_permutevar8x32_epi32(bytes, order));
  }
  detail::own_states_of(p + i, n - i, lo, hi, out + i);
}
#endif

// OwnBits of the row of n values at p: u (lo <= p <= hi: unknown) and o (p > hi: occupied), the
// words cleared first, bits past n 0.
void own_bits_of(const float* p, std::size_t n, float lo, float hi, word_t* u, word_t* o) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) u[i] = o[i] = 0;
  for (std::size_t x = 0; x < n; ++x) {
    u[x / 64] |= static_cast<std::uint64_t>(!(p[x] < lo) && !(p[x] > hi)) << (x % 64);
    o[x / 64] |= static_cast<std::uint64_t>(p[x] > hi) << (x % 64);
  }
}

#ifdef OCCSEG_CREATE_AVX2
// own_bits_of() 64 voxels per step (8 compares of 8 each; the scalar one takes the rest). NaN
// counts as unknown, as in own_states_of() (it never gets this far: the map is rejected).
__attribute__((target("avx2"))) void own_bits_avx2(const float* p, std::size_t n, float lo, float hi, word_t* u,
                                                   word_t* o) {
  const __m256 l = _mm256_set1_ps(lo), h = _mm256_set1_ps(hi);
  std::size_t i = 0;
  for (; i + 64 <= n; i += 64) {
    std::uint64_t uw = 0, ow = 0;
    for (int j = 0; j < 8; ++j) {
      const __m256 a = _mm256_loadu_ps(p + i + 8 * j);
      const __m256 in = _mm256_and_ps(_mm256_cmp_ps(a, l, _CMP_NLT_UQ), _mm256_cmp_ps(a, h, _CMP_NGT_UQ));
      uw |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(in))) << (8 * j);
      ow |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(a, h, _CMP_GT_OQ))))
            << (8 * j);
    }
    u[i / 64] = uw;
    o[i / 64] = ow;
  }
  if (i < n) own_bits_of(p + i, n - i, lo, hi, u + i / 64, o + i / 64);
}

// own_bits_avx2() with AVX-512 compares into mask registers, 16 voxels each.
__attribute__((target("avx512f"))) void own_bits_avx512(const float* p, std::size_t n, float lo, float hi, word_t* u,
                                                         word_t* o) {
  const __m512 l = _mm512_set1_ps(lo), h = _mm512_set1_ps(hi);
  std::size_t i = 0;
  for (; i + 64 <= n; i += 64) {
    std::uint64_t uw = 0, ow = 0;
    for (int j = 0; j < 4; ++j) {
      const __m512 a = _mm512_loadu_ps(p + i + 16 * j);
      const __mmask16 in = _mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(a, l, _CMP_NLT_UQ), a, h, _CMP_NGT_UQ);
      uw |= static_cast<std::uint64_t>(in) << (16 * j);
      ow |= static_cast<std::uint64_t>(_mm512_cmp_ps_mask(a, h, _CMP_GT_OQ)) << (16 * j);
    }
    u[i / 64] = uw;
    o[i / 64] = ow;
  }
  if (i < n) own_bits_of(p + i, n - i, lo, hi, u + i / 64, o + i / 64);
}
#endif

}  // namespace

detail::OwnBitsStore detail::pack_own_bits(const std::uint8_t* own, const Dims& d, int threads) {
  OwnBitsStore s;
  const std::size_t words = (d.nx + 63) / 64;
  s.unknown.resize(d.ny * d.nz * words);
  s.occupied.resize(d.ny * d.nz * words);
  pack_own_bits(own, d, threads, s.unknown.data(), s.occupied.data());
  s.bits = OwnBits{s.unknown.data(), s.occupied.data(), words};
  return s;
}

void detail::pack_own_bits(const std::uint8_t* own, const Dims& d, int threads, std::uint64_t* unknown,
                           std::uint64_t* occupied) {
  const std::size_t words = (d.nx + 63) / 64;
  parallel_for(d.ny * d.nz, threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r) {
      const std::uint8_t* row = own + r * d.nx;
      constexpr auto kUnknownOwn = static_cast<std::uint8_t>(State::unknown);
      constexpr auto kOccupiedOwn = static_cast<std::uint8_t>(State::occupied);
      pack_equal(row, d.nx, kUnknownOwn, reinterpret_cast<word_t*>(unknown) + r * words);
      pack_equal(row, d.nx, kOccupiedOwn, reinterpret_cast<word_t*>(occupied) + r * words);
    }
  });
}

detail::CellRows::CellRows(const Grid& grid, std::uint8_t* own, float lo, float hi, std::uint64_t* unknown_bits,
                           std::uint64_t* occupied_bits)
    : grid_(&grid),
      own_(own),
      unknown_(unknown_bits),
      occupied_(occupied_bits),
      lo_(lo),
      hi_(hi),
      ncx_((grid.dims.nx + kMeanCell - 1) / kMeanCell),
      ncy_((grid.dims.ny + kMeanCell - 1) / kMeanCell),
      avx2_(cpu_has_avx2() && texture_kernel() >= TextureKernel::avx2),
      avx512_(cpu_has_avx512() && texture_kernel() >= TextureKernel::avx512),
      sum_(ncx_ * ncy_ * ((grid.dims.nz + kMeanCell - 1) / kMeanCell), 0.0) {}

void detail::CellRows::add_row(std::size_t y, std::size_t z) {
  constexpr std::size_t c = kMeanCell;
  static_assert(kMeanCell == 8, "the row loop below adds eight voxels per cell");
  const std::size_t nx = grid_->dims.nx, i0 = nx * (y + grid_->dims.ny * z);
  const float* const row = grid_->p.data() + i0;
  if (!own_ && unknown_ && occupied_) {  // the own states as bits only, straight from the values
    const std::size_t w = (nx + 63) / 64 * (y + grid_->dims.ny * z);
    word_t* const u = reinterpret_cast<word_t*>(unknown_) + w;
    word_t* const o = reinterpret_cast<word_t*>(occupied_) + w;
#ifdef OCCSEG_CREATE_AVX2
    if (avx512_) own_bits_avx512(row, nx, lo_, hi_, u, o);
    else if (avx2_) own_bits_avx2(row, nx, lo_, hi_, u, o);
    else
#endif
      own_bits_of(row, nx, lo_, hi_, u, o);
  } else if (own_) {
#ifdef OCCSEG_CREATE_AVX2
    if (avx2_) own_states_avx2(row, nx, lo_, hi_, own_ + i0);
    else
#endif
      own_states_of(row, nx, lo_, hi_, own_ + i0);
    if (unknown_) {
      word_t* const u = reinterpret_cast<word_t*>(unknown_) + (nx + 63) / 64 * (y + grid_->dims.ny * z);
      const auto unknown = static_cast<std::uint8_t>(State::unknown);
#ifdef OCCSEG_CREATE_AVX2
      if (avx2_) pack_equal_avx2(own_ + i0, nx, unknown, u);
      else
#endif
        pack_equal(own_ + i0, nx, unknown, u);
    }
  }
  double* const sums = sum_.data() + ncx_ * (y / c + ncy_ * (z / c));
  std::size_t cx = 0;
#ifdef OCCSEG_CREATE_AVX2
  if (avx2_) {
    cx = nx / c / 8 * 8;
    if (avx512_) add_cells_avx512(row, sums, cx);
    else add_cells_avx2(row, sums, cx);
  }
#endif
  for (; (cx + 1) * c <= nx; ++cx) {  // whole cells: eight additions each
    const float* v = row + cx * c;
    double acc = sums[cx];
    acc += v[0], acc += v[1], acc += v[2], acc += v[3], acc += v[4], acc += v[5], acc += v[6], acc += v[7];
    sums[cx] = acc;
  }
  if (cx < ncx_) {  // the cell cut by the far face
    double acc = sums[cx];
    for (std::size_t x = cx * c; x < nx; ++x) acc += row[x];
    sums[cx] = acc;
  }
}

namespace {

constexpr auto kFreeState = static_cast<std::uint8_t>(State::free);
constexpr auto kUnknownState = static_cast<std::uint8_t>(State::unknown);
constexpr auto kOccupiedState = static_cast<std::uint8_t>(State::occupied);

// 0xFF in each byte of `eight` equal to v, 0 in the others (exact: no borrow between bytes).
inline std::uint64_t bytes_equal(std::uint64_t eight, std::uint8_t v) {
  constexpr std::uint64_t low7 = 0x7F7F7F7F7F7F7F7Full, high = 0x8080808080808080ull;
  const std::uint64_t x = eight ^ (0x0101010101010101ull * v);  // 0 where equal
  const std::uint64_t nonzero = ((x & low7) + low7) | x;         // bit 7 of a byte: byte != 0
  return ((~nonzero & high) >> 7) * 0xFF;
}

// Block by block: any set of disjoint blocks. Voxels outside every block are left free.
void create_by_blocks(const Grid& grid, const std::vector<Block>& blocks, const Params& params, std::uint8_t* own,
                      float lo, float hi, std::uint8_t* states) {
  // Blocks in scan order of their corners: division lists them tree by tree, octant by octant,
  // and neighbours along x (whose 32-byte rows share cache lines) came far apart.
  std::vector<std::pair<std::uint64_t, std::size_t>> order(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) order[i] = {grid.index(blocks[i].lo[0], blocks[i].lo[1], blocks[i].lo[2]), i};
  std::sort(order.begin(), order.end());
  parallel_for_dynamic(blocks.size(), params.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {  // blocks are disjoint: no two threads write one voxel
      const Block& blk = blocks[order[k].second];
      const std::size_t width = blk.hi[0] - blk.lo[0];
      if (own)  // the block's rows are about to be read for its mean: in cache for both
        for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
          for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) {
            const std::size_t at = grid.index(blk.lo[0], y, z);
            detail::own_states_of(grid.p.data() + at, width, lo, hi, own + at);
          }
      const auto s = static_cast<std::uint8_t>(params.state_of(mean_occupancy(grid, blk)));
      for (std::uint32_t z = blk.lo[2]; z < blk.hi[2]; ++z)
        for (std::uint32_t y = blk.lo[1]; y < blk.hi[1]; ++y) std::memset(states + grid.index(blk.lo[0], y, z), s, width);
    }
  });
}

// Row by row, for blocks that tile the map on the lattice of kMeanCell^3 cells (division's leaves
// for Smin >= 8: cubes aligned to their size, clipped by the map's far faces). Each row adds
// its voxels to the running sums of the cells it crosses, in the row's order, so each cell's
// voxels arrive in scan order; the block sums add their cells' sums in scan order of the cells:
// mean_occupancy(), bit for bit. The map is read once, as a stream, and every row adds into
// nx / 8 independent sums (one chain of additions through a whole block, as a block-by-block
// sum in scan order needs, ran at the latency of an addition). Returns false (nothing written)
// for other blocks. With `means`, the blocks' means go there and no states are written.
bool create_by_rows(const Grid& grid, const std::vector<Block>& blocks, const Params& params, detail::CellRows& rows,
                    bool summed, std::uint8_t* states, std::vector<double>* means = nullptr,
                    detail::GrowthRows* growth = nullptr) {
  const Dims& d = grid.dims;
  const std::size_t dim[3] = {d.nx, d.ny, d.nz};
  constexpr std::size_t c = kMeanCell;
  for (const Block& b : blocks)
    for (int a = 0; a < 3; ++a) {
      if (b.hi[a] <= b.lo[a] || b.hi[a] > dim[a]) return false;
      if (b.lo[a] % c || (b.hi[a] != dim[a] && b.hi[a] % c)) return false;  // off the lattice
    }
  const std::size_t ncx = rows.cells_x(), ncy = rows.cells_y(), ncz = (d.nz + c - 1) / c;
  // fn(index of the cell) for the cells of block b, in scan order.
  const auto for_cells = [&](const Block& b, auto&& fn) {
    for (std::size_t z = b.lo[2] / c; z < (b.hi[2] + c - 1) / c; ++z)
      for (std::size_t y = b.lo[1] / c; y < (b.hi[1] + c - 1) / c; ++y)
        for (std::size_t x = b.lo[0] / c; x < (b.hi[0] + c - 1) / c; ++x) fn(x + ncx * (y + ncy * z));
  };
  // Which block each cell belongs to; every cell exactly once, or this is no tiling.
  std::vector<std::uint32_t> cell(ncx * ncy * ncz, ~0u);
  bool tiling = true;
  for (std::size_t k = 0; k < blocks.size() && tiling; ++k)
    for_cells(blocks[k], [&](std::size_t i) {
      tiling = tiling && cell[i] == ~0u;
      cell[i] = static_cast<std::uint32_t>(k);
    });
  if (!tiling) return false;
  for (std::uint32_t id : cell)
    if (id == ~0u) return false;

  // The cells' sums, a row of cells (c planes of c rows) per task, unless they are summed already.
  if (!summed)
    parallel_for_dynamic(ncy * ncz, params.threads, [&](std::size_t t0, std::size_t t1) {
      for (std::size_t t = t0; t < t1; ++t) {
        const std::size_t cy = t % ncy, cz = t / ncy;
        for (std::size_t z = cz * c; z < std::min(d.nz, cz * c + c); ++z)
          for (std::size_t y = cy * c; y < std::min(d.ny, cy * c + c); ++y) rows.add_row(y, z);
      }
    });
  const std::vector<double>& cell_sum = rows.sums();
  // Each block's sum over its cells in scan order, each cell's state, then the states row by row.
  std::vector<std::uint8_t> cell_state(cell.size());
  if (means) means->assign(blocks.size(), 0.0);
  parallel_for(blocks.size(), params.threads, [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k) {
      const Block& b = blocks[k];
      double sum = 0;
      for_cells(b, [&](std::size_t i) { sum += cell_sum[i]; });
      const double mean = sum / static_cast<double>(b.volume());
      if (means) (*means)[k] = mean;
      const auto st = static_cast<std::uint8_t>(params.state_of(mean));
      for_cells(b, [&](std::size_t i) { cell_state[i] = st; });
    }
  });
  if (means) return true;
  // The growth's masks (GrowthRows): a cell covers 8 voxels of a row, a byte of a mask word, so
  // word i of a row holds cells 8i .. 8i + 7 (static_assert below), each byte 0xFF or 0.
  static_assert(kMeanCell == 8, "a cell must be one byte of the growth's mask words");
  const std::size_t words = (d.nx + 63) / 64;
  const bool defer = growth && growth->defer_states;  // the growth writes the states
  detail::word_t* const W = growth ? reinterpret_cast<detail::word_t*>(growth->scratch) : nullptr;
  detail::word_t* const C = W ? W + d.ny * d.nz * words : nullptr;
  const std::uint64_t last = d.nx % 64 ? (std::uint64_t(1) << (d.nx % 64)) - 1 : ~std::uint64_t(0);
  parallel_for(d.ny * d.nz, params.threads, [&](std::size_t r0, std::size_t r1) {
    // The masks of the row of cells the last row was in (the c rows of a row of cells share them).
    std::vector<std::uint64_t> cells_w(W ? words : 0), cells_c(W ? words : 0);
    std::size_t cells_row = ~std::size_t(0);
    bool cells_occupied = false;
    for (std::size_t r = r0; r < r1; ++r) {
      const std::size_t cr = r % d.ny / c + ncy * (r / d.ny / c);
      const std::uint8_t* cs = cell_state.data() + ncx * cr;
      if (!defer) {
        std::uint8_t* row = states + d.nx * r;
        std::size_t cx = 0;
        for (; (cx + 1) * c <= d.nx; ++cx) {  // one 8-byte store per cell
          const std::uint64_t eight = 0x0101010101010101ull * cs[cx];
          std::memcpy(row + cx * c, &eight, c);
        }
        if (cx < ncx) std::memset(row + cx * c, cs[cx], d.nx - cx * c);
      }
      if (!W) continue;
      if (cr != cells_row) {
        cells_row = cr;
        for (std::size_t i = 0; i < words; ++i) {
          std::uint64_t eight = ~std::uint64_t(0);  // past the last cell: no state
          std::memcpy(&eight, cs + 8 * i, std::min<std::size_t>(8, ncx - 8 * i));
          const std::uint64_t keep = i + 1 == words ? last : ~std::uint64_t(0);
          cells_w[i] = bytes_equal(eight, kUnknownState) & keep;
          cells_c[i] = bytes_equal(eight, kFreeState) & keep;
        }
        cells_occupied = std::memchr(cs, kOccupiedState, ncx) != nullptr;
      }
      for (std::size_t i = 0; i < words; ++i) {
        W[r * words + i] = cells_w[i];
        C[r * words + i] = cells_c[i] & growth->unknown_bits[r * words + i];
      }
      growth->occupied_rows[r] = cells_occupied;
    }
  });
  if (growth) growth->filled = true;
  if (defer) growth->cell_states = std::move(cell_state);
  return true;
}

// V: std::vector (zeroed first) for the public create_segments(), UninitVector for the pipeline,
// whose states are all written here, in parallel.
template <class V>
V create(const Grid& grid, const std::vector<Block>& blocks, const Params& params, std::uint8_t* own,
         detail::CellRows* summed = nullptr, detail::GrowthRows* growth = nullptr) {
  V states;
  resize_huge(states, grid.dims.count());
  float lo = 0, hi = 0;
  if (own) detail::float_bounds(params.free_below, params.occupied_above, lo, hi);
  std::optional<detail::CellRows> fresh;  // the rows are summed here unless they were (not copied)
  detail::CellRows& rows = summed ? *summed : fresh.emplace(grid, own, lo, hi);
  if (!create_by_rows(grid, blocks, params, rows, summed != nullptr, states.data(), nullptr, growth))
    create_by_blocks(grid, blocks, params, own, lo, hi, states.data());
  return states;
}

}  // namespace

std::vector<double> detail::block_means_by_rows(const Grid& grid, const std::vector<Block>& blocks, int threads) {
  Params p;
  p.threads = threads;
  std::vector<double> means;
  detail::CellRows rows(grid, nullptr, 0, 0);
  create_by_rows(grid, blocks, p, rows, false, nullptr, &means);
  return means;
}

std::vector<std::uint8_t> create_segments(const Grid& grid, const std::vector<Block>& blocks,
                                          const Params& params) {
  return create<std::vector<std::uint8_t>>(grid, blocks, params, nullptr);
}

UninitVector<std::uint8_t> detail::create_segments_and_own_states(const Grid& grid, const std::vector<Block>& blocks,
                                                                  const Params& params, std::uint8_t* own,
                                                                  CellRows* summed, GrowthRows* growth) {
  return create<UninitVector<std::uint8_t>>(grid, blocks, params, own, summed, growth);
}

}  // namespace occseg
