#include "rules/departures.hpp"

#include <algorithm>
#include <cstdint>
#include <mutex>

#include "occseg/parallel.hpp"
#include "util/bit_rows.hpp"
#include "kernels/cpu_features.hpp"
#include "util/huge_pages.hpp"
#include "stages/own_states.hpp"
#include "stages/refine.hpp"
#include "stages/texture.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace occseg {

namespace {

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);

// The opening works on bit masks, 64 voxels of a row per word: its six passes then stream 1/8 of
// the memory the byte masks took (13 MB per pass on a 320 x 320 x 128 map). Row r of the mask is
// words [r * W, (r + 1) * W), W = ceil(nx / 64), voxel x at bit x % 64 of word x / 64; the bits
// past nx in a row's last word are kept 0 (bit_rows_internal.hpp). The words live in the mask's
// own vector, or in scratch storage handed in (segment() gives part of the label array, which
// then holds no labels yet); every row is written before it is read, so that storage is not
// cleared.
using detail::word_t;
struct BitMask {
  std::size_t nx = 0, rows = 0, W = 0;
  std::vector<std::uint64_t> own_words;
  word_t* w = nullptr;
  BitMask(std::size_t nx_, std::size_t rows_, void* storage = nullptr) : nx(nx_), rows(rows_), W((nx_ + 63) / 64) {
    if (storage) {
      w = static_cast<word_t*>(storage);
    } else {
      own_words.assign(rows * W, 0);
      w = reinterpret_cast<word_t*>(own_words.data());
    }
  }
  static std::size_t bytes(std::size_t nx, std::size_t rows) { return rows * ((nx + 63) / 64) * sizeof(std::uint64_t); }
  word_t* row(std::size_t r) { return w + r * W; }
  const word_t* row(std::size_t r) const { return w + r * W; }
  std::uint64_t tail() const { return nx % 64 ? (std::uint64_t(1) << (nx % 64)) - 1 : ~std::uint64_t(0); }
};

// One axis of a box erosion (AND; the outside counts as 1) or dilation (OR; the outside counts as
// 0) of radius r, from `in` to `out`: the same windows, clipped by the map, as the byte version it
// replaced (docs/performance.md). Along x, rows [r0, r1). Each word is shifted against the words
// before and after it, which the loop carries along in registers (reloading them with a test for
// the row's ends at every shift took 0.64 of the opening's 1.1 ms on the scene).
template <bool Erode>
void box_x_rows(const BitMask& in, BitMask& out, std::size_t r0, std::size_t r1, int r) {
  const std::size_t W = in.W;
  const std::uint64_t tail = in.tail();
  // Erosion: the bits past nx count as 1 while shifting, then go back to 0.
  const std::uint64_t pad = Erode ? ~tail : 0, outside = Erode ? ~std::uint64_t(0) : 0;
  // Radii of 64 or more never occur (gap_radius <= 16), so k < 64.
  const unsigned K = static_cast<unsigned>(std::min<std::size_t>(static_cast<std::size_t>(r), in.nx - 1));
  for (std::size_t rw = r0; rw < r1; ++rw) {
    const word_t* a = in.row(rw);
    word_t* o = out.row(rw);
    std::uint64_t prev = outside, cur = W == 1 ? a[0] | pad : a[0];
    for (std::size_t i = 0; i < W; ++i) {
      const std::uint64_t next = i + 1 < W ? (i + 2 == W ? a[i + 1] | pad : a[i + 1]) : outside;
      std::uint64_t v = cur;
      for (unsigned k = 1; k <= K; ++k) {
        const std::uint64_t rt = (cur >> k) | (next << (64 - k)), lt = (cur << k) | (prev >> (64 - k));
        v = Erode ? (v & rt & lt) : (v | rt | lt);
      }
      o[i] = i + 1 == W ? v & tail : v;
      prev = cur;
      cur = next;
    }
  }
}

void box_x(const BitMask& in, BitMask& out, std::size_t r0, std::size_t r1, int r, bool erode) {
  if (erode) box_x_rows<true>(in, out, r0, r1, r);
  else box_x_rows<false>(in, out, r0, r1, r);
}

// One axis of the box erosion or dilation along y, for every row of one plane (ny rows of W
// words, contiguous; `in` and `out` apart): row y of out takes rows y - r .. y + r of in, clipped
// by the plane (the same windows as box_x's, and as the z pass's over planes).
void box_y_plane(const word_t* in, word_t* out, std::size_t ny, std::size_t W, int r, bool erode) {
  const std::size_t P = ny * W;
  std::copy(in, in + P, out);
  for (std::size_t k = 1; k <= static_cast<std::size_t>(r) && k < ny; ++k) {
    const std::size_t off = k * W;  // out[y] with in[y + k] (y + k < ny), then with in[y - k] (y >= k)
    if (erode) {
      for (std::size_t i = 0; i + off < P; ++i) out[i] &= in[i + off];
      for (std::size_t i = off; i < P; ++i) out[i] &= in[i - off];
    } else {
      for (std::size_t i = 0; i + off < P; ++i) out[i] |= in[i + off];
      for (std::size_t i = off; i < P; ++i) out[i] |= in[i - off];
    }
  }
}

// out[x] = bit x of the row, and own[x] at 0.5 (the opening only shrinks the 0.5 mask; kept
// anyway).
void unpack_half(const word_t* bits, const std::uint8_t* own, std::size_t nx, std::uint8_t* out) {
  std::size_t x = 0;
#ifdef __SSE2__
  const __m128i one = _mm_set1_epi8(1), half = _mm_set1_epi8(static_cast<char>(kUnknown));
  for (; x + 16 <= nx; x += 16) {
    const __m128i set = detail::bytes_of_bits16(bits, x);
    const __m128i is_half = _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(own + x)), half);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm_and_si128(_mm_and_si128(set, is_half), one));
  }
#endif
  for (; x < nx; ++x) out[x] = static_cast<std::uint8_t>(((bits[x / 64] >> (x % 64)) & 1) & (own[x] == kUnknown));
}

// The per-voxel rules on one voxel: its state s, own state o, region bit and whether it touches
// an occupied voxel (own states of its six neighbours).
inline std::uint8_t rule(std::uint8_t s, std::uint8_t o, std::uint8_t region, bool touches) {
  const std::uint8_t gap = ((s == kFree) & touches) ? kUnknown : s;
  return o != kUnknown ? o : (region ? kUnknown : gap);
}

// The bits of row r's voxels that touch an occupied voxel: its occupied neighbours along x (the
// row's own bits shifted; the bits past nx are 0, so nothing comes in past the ends) and along y
// and z (rows ym, yp, zm, zp of occupied bits; rows of zeros outside the map). The rules work on
// bits: 64 voxels per operation, and no scalar ends where a neighbour is outside the row.
void touching_bits(const word_t* o, const word_t* ym, const word_t* yp, const word_t* zm, const word_t* zp,
                   std::size_t W, std::uint64_t* t) {
  for (std::size_t i = 0; i < W; ++i) {
    const std::uint64_t left = (o[i] << 1) | (i > 0 ? o[i - 1] >> 63 : 0);       // x - 1 occupied
    const std::uint64_t right = (o[i] >> 1) | (i + 1 < W ? o[i + 1] << 63 : 0);  // x + 1 occupied
    t[i] = left | right | ym[i] | yp[i] | zm[i] | zp[i];
  }
}

// The rules on a row of n voxels (states st, in place) from bit rows: u and o its own states
// (OwnBits), reg its region bits, t touching_bits(). Appends the seeds of the gap flood (a gap
// voxel the rules left unknown that touches an occupied voxel), `first` + x, to `seeds` in x
// order. The portable kernel, and the reference for the AVX2 one.
void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg, const std::uint64_t* t,
               std::size_t n, std::size_t first, std::vector<std::size_t>& seeds) {
  for (std::size_t x = 0; x < n; ++x) {
    const std::size_t i = x / 64;
    const unsigned b = x % 64;
    const bool unknown = (u[i] >> b) & 1u, region = (reg[i] >> b) & 1u, touches = (t[i] >> b) & 1u;
    const std::uint8_t own = unknown ? kUnknown : (((o[i] >> b) & 1u) ? kOccupied : kFree);
    st[x] = rule(st[x], own, region, touches);
    if (unknown && !region && touches && st[x] == kUnknown) seeds.push_back(first + x);
  }
}

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_RULES_AVX2 1
// rule() on voxels x .. x + 31 of a row, in place, from bit rows as in rules_row(); returns the
// seeds among them (0xFF).
__attribute__((target("avx2"))) inline __m256i rules_step_avx2(std::uint8_t* st, const word_t* u, const word_t* o,
                                                               const word_t* reg, const word_t* t, std::size_t x) {
  const __m256i unk = _mm256_set1_epi8(static_cast<char>(kUnknown)), fre = _mm256_set1_epi8(static_cast<char>(kFree));
  const __m256i occ = _mm256_set1_epi8(static_cast<char>(kOccupied));
  __m256i* const at = reinterpret_cast<__m256i*>(st + x);
  const __m256i s = _mm256_loadu_si256(at);
  const __m256i own_unknown = detail::bytes_of_bits32(u, x), region = detail::bytes_of_bits32(reg, x);
  const __m256i touches = detail::bytes_of_bits32(t, x);
  const __m256i known = _mm256_and_si256(detail::bytes_of_bits32(o, x), occ);  // free (0) or occupied
  const __m256i gap = _mm256_blendv_epi8(s, unk, _mm256_and_si256(_mm256_cmpeq_epi8(s, fre), touches));
  const __m256i res = _mm256_blendv_epi8(known, _mm256_blendv_epi8(gap, unk, region), own_unknown);
  _mm256_storeu_si256(at, res);
  const __m256i gap_touching = _mm256_andnot_si256(region, _mm256_and_si256(own_unknown, touches));
  return _mm256_and_si256(gap_touching, _mm256_cmpeq_epi8(res, unk));
}

// rules_row() for rows of at least 32 voxels, 32 voxels per step in hand-written AVX2; the last
// step overlaps the one before instead of a scalar tail (the rules are idempotent: a second
// application to a result gives the result), and only its new voxels' seeds are taken. The seeds
// come out of the same steps: a superset of them (before the touching bits) sent most rows of the
// scene through a scalar search (0.6 of the rules' 2.2 ms).
__attribute__((target("avx2"))) void rules_row_avx2(std::uint8_t* st, const word_t* u, const word_t* o,
                                                    const word_t* reg, const std::uint64_t* t, std::size_t n,
                                                    std::size_t first, std::vector<std::size_t>& seeds) {
  const auto* const tw = reinterpret_cast<const word_t*>(t);
  // Steps at x0 = 0, 32, ... and, for the last n % 32 voxels, at n - 32, whose seeds below
  // `done` (bit k: voxel x0 + k) the step before reported already. (No lambda: it would not be
  // compiled for AVX2.)
  for (std::size_t done = 0; done < n;) {
    const std::size_t x0 = std::min(done, n - 32);
    auto m = static_cast<std::uint32_t>(_mm256_movemask_epi8(rules_step_avx2(st, u, o, reg, tw, x0)));
    if (done > x0) m &= ~0u << (done - x0);
    for (; m; m &= m - 1) seeds.push_back(first + x0 + static_cast<std::size_t>(__builtin_ctz(m)));
    done = x0 + 32;
  }
}

// rules_row() 64 voxels per step in AVX-512 (F, BW): the bit words are the blend and compare
// masks themselves, so nothing is spread into bytes; the last n % 64 voxels are one masked step.
__attribute__((target("avx512f,avx512bw"))) void rules_row_avx512(std::uint8_t* st, const word_t* u, const word_t* o,
                                                                  const word_t* reg, const std::uint64_t* t,
                                                                  std::size_t n, std::size_t first,
                                                                  std::vector<std::size_t>& seeds) {
  const __m512i unk = _mm512_set1_epi8(static_cast<char>(kUnknown)), fre = _mm512_set1_epi8(static_cast<char>(kFree));
  const __m512i occ = _mm512_set1_epi8(static_cast<char>(kOccupied));
  for (std::size_t i = 0; 64 * i < n; ++i) {
    const std::size_t x = 64 * i;
    const __mmask64 in = n - x >= 64 ? ~__mmask64(0) : (__mmask64(1) << (n - x)) - 1;
    const __m512i s = _mm512_maskz_loadu_epi8(in, st + x);
    const __mmask64 gap = _mm512_cmpeq_epi8_mask(s, fre) & t[i];           // free, touching: unknown
    const __m512i res_unknown = _mm512_mask_mov_epi8(s, reg[i] | gap, unk);  // own state unknown
    const __m512i res = _mm512_mask_blend_epi8(u[i], _mm512_maskz_mov_epi8(o[i], occ), res_unknown);
    _mm512_mask_storeu_epi8(st + x, in, res);
    std::uint64_t m = u[i] & ~reg[i] & t[i] & _mm512_cmpeq_epi8_mask(res, unk) & in;
    for (; m; m &= m - 1) seeds.push_back(first + x + static_cast<std::size_t>(__builtin_ctzll(m)));
  }
}
#endif

// The rule rows' kernel: the fastest the processor has up to detail::set_texture_kernel()'s
// setting (which the tests step through).
enum class RulesKernel { portable, avx2, avx512 };
RulesKernel rules_kernel(std::size_t nx) {
#ifdef OCCSEG_RULES_AVX2
  const detail::TextureKernel k = detail::texture_kernel();
  if (k >= detail::TextureKernel::avx512 && cpu_has_avx512()) return RulesKernel::avx512;
  if (k >= detail::TextureKernel::avx2 && cpu_has_avx2() && nx >= 32) return RulesKernel::avx2;
#endif
  (void)nx;
  return RulesKernel::portable;
}

}  // namespace

namespace {

// Rule 2's regions as a bit mask (a row of bits per row of voxels; bit set: the voxel is at 0.5
// and in a region). apply_voxel_rules() reads it row by row; the byte mask of unknown_regions()
// is made from it only when asked for: allocating, zero-filling and writing 13 MB of bytes, and
// reading them back, cost more than the opening itself.
BitMask region_bits(const detail::OwnBits& own, const Dims& d, const Params& params, std::uint8_t* scratch = nullptr,
                    std::size_t scratch_bytes = 0) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, rows = ny * nz;
  const int r = params.gap_radius;
  BitMask out(nx, rows, scratch && BitMask::bytes(nx, rows) <= scratch_bytes ? scratch : nullptr);
  // The 0.5 bits: the own states' unknown bits.
  const BitMask half(nx, rows, const_cast<std::uint64_t*>(own.unknown));
  if (r <= 0) {  // no opening: every 0.5 voxel is in a region
    parallel_for_dynamic(rows, params.threads, [&](std::size_t r0, std::size_t r1) {
      for (std::size_t rw = r0; rw < r1; ++rw) std::copy(half.row(rw), half.row(rw) + out.W, out.row(rw));
    });
    return out;
  }
  // Opening = erosion then dilation, each three axis passes in the order x, y, z, plane by plane
  // in one pass: each thread takes a stretch of planes and keeps the last 2r + 1 planes eroded in
  // x and y (Exy) and those fully eroded and dilated in x and y (Dxy) in rings of its own (12.8 KB
  // a plane on the scene: they stay in L1 and L2), where three passes over whole masks in the
  // label array, with two waits for all threads, took 1.75 ms on the scene. Per plane z:
  //   Exy(z) = erode_y(erode_x(0.5 bits of z))
  //   Dxy(z) = dilate_y(dilate_x(AND of Exy(z - r .. z + r)))      (planes outside the map: skipped)
  //   region(z) = OR of Dxy(z - r .. z + r)
  // The first and last planes of a stretch are computed from the 2r planes around it (more of
  // the same work on each thread, so the threads take fixed stretches).
  const std::size_t R = static_cast<std::size_t>(r), slots = 2 * R + 1, W = out.W, P = ny * W;
  parallel_for(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::uint64_t> exy(slots * P), dxy(slots * P), t1(P), t2(P);
    BitMask tmp(nx, ny, t1.data()), both(nx, ny, t2.data());
    const auto ring = [&](std::vector<std::uint64_t>& v, std::size_t z) {
      return BitMask(nx, ny, v.data() + (z % slots) * P);
    };
    const auto whole = [&](BitMask& m, std::size_t z) { return BitMask(nx, ny, m.w + z * P); };
    // Planes z of the union (or intersection) of ring planes [a, b] into `to`.
    const auto combine = [&](std::vector<std::uint64_t>& v, std::size_t a, std::size_t b, BitMask& to, bool erode) {
      const word_t* first = ring(v, a).w;
      std::copy(first, first + P, to.w);
      for (std::size_t z = a + 1; z <= b; ++z) {
        const word_t* src = ring(v, z).w;
        if (erode)
          for (std::size_t i = 0; i < P; ++i) to.w[i] &= src[i];
        else
          for (std::size_t i = 0; i < P; ++i) to.w[i] |= src[i];
      }
    };
    const std::size_t dlo = z0 >= R ? z0 - R : 0, dhi = std::min(nz, z1 + R);  // the Dxy planes needed
    std::size_t next_e = dlo >= R ? dlo - R : 0;                                 // the next Exy to make
    const auto emit = [&](std::size_t z) {  // region(z), once Dxy(z - r .. z + r) are made
      BitMask to = whole(out, z);
      combine(dxy, z >= R ? z - R : 0, std::min(nz - 1, z + R), to, false);
    };
    for (std::size_t zz = dlo; zz < dhi; ++zz) {
      for (; next_e < std::min(nz, zz + R + 1); ++next_e) {
        const BitMask in(nx, ny, const_cast<word_t*>(half.w + next_e * P));
        box_x(in, tmp, 0, ny, r, true);
        box_y_plane(tmp.w, ring(exy, next_e).w, ny, W, r, true);
      }
      combine(exy, zz >= R ? zz - R : 0, std::min(nz - 1, zz + R), both, true);
      box_x(both, tmp, 0, ny, r, false);
      box_y_plane(tmp.w, ring(dxy, zz).w, ny, W, r, false);
      if (zz >= z0 + R && zz - R < z1) emit(zz - R);
    }
    for (std::size_t z = std::max(z0, dhi >= R ? dhi - R : 0); z < z1; ++z) emit(z);  // windows cut by the far face
  });
  return out;
}

inline bool bit(const BitMask& m, std::size_t row, std::size_t x) { return (m.row(row)[x / 64] >> (x % 64)) & 1u; }

}  // namespace

std::vector<std::uint8_t> unknown_regions(const std::vector<std::uint8_t>& own, const Dims& d, const Params& params) {
  const detail::OwnBitsStore bits = detail::pack_own_bits(own.data(), d, params.threads);
  const BitMask a = region_bits(bits.bits, d, params);
  std::vector<std::uint8_t> m;
  resize_huge(m, own.size());
  const std::size_t nx = d.nx;
  parallel_for_dynamic(a.rows, params.threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t rw = r0; rw < r1; ++rw) unpack_half(a.row(rw), own.data() + rw * nx, nx, m.data() + rw * nx);
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
void flood_gaps_from_objects(std::uint8_t* st, const detail::OwnBits& own, const BitMask& region, const Dims& d,
                             std::vector<std::size_t>& queue) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sz = nx * ny;
  auto gap = [&](std::size_t i) { return own.at(i / nx, i % nx) == kUnknown && !bit(region, i / nx, i % nx); };
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

void detail::apply_voxel_rules(std::uint8_t* st, const OwnBits& own, const Dims& d, const Params& params,
                               std::uint8_t* scratch, std::size_t scratch_bytes) {
  const BitMask region = region_bits(own, d, params, scratch, scratch_bytes);
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, W = own.words;
  const std::vector<std::uint64_t> none(W, 0);  // outside the map: no occupied neighbour
  // Reads only own states and each voxel's own entry of st, so rows are independent. The seeds of
  // the gap flood are gathered on the way, slab by slab.
  std::vector<std::size_t> seeds;
  std::mutex seeds_mutex;
  const RulesKernel kernel = rules_kernel(nx);
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::size_t> mine;
    std::vector<std::uint64_t> touching(W);
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t r = y + ny * z, i = nx * r;
        const auto* const u = reinterpret_cast<const word_t*>(own.unknown) + r * W;
        const auto* const o = reinterpret_cast<const word_t*>(own.occupied) + r * W;
        const auto* const out = reinterpret_cast<const word_t*>(none.data());
        touching_bits(o, y > 0 ? o - W : out, y + 1 < ny ? o + W : out, z > 0 ? o - ny * W : out,
                      z + 1 < nz ? o + ny * W : out, W, touching.data());
#ifdef OCCSEG_RULES_AVX2
        if (kernel == RulesKernel::avx512) {
          rules_row_avx512(st + i, u, o, region.row(r), touching.data(), nx, i, mine);
          continue;
        }
        if (kernel == RulesKernel::avx2) {
          rules_row_avx2(st + i, u, o, region.row(r), touching.data(), nx, i, mine);
          continue;
        }
#endif
        rules_row(st + i, u, o, region.row(r), touching.data(), nx, i, mine);
      }
    std::lock_guard<std::mutex> lock(seeds_mutex);
    seeds.insert(seeds.end(), mine.begin(), mine.end());
  });
  flood_gaps_from_objects(st, own, region, d, seeds);
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                       const Params& params) {
  const detail::OwnBitsStore bits = detail::pack_own_bits(own.data(), d, params.threads);
  detail::apply_voxel_rules(st.data(), bits.bits, d, params, nullptr, 0);
}

std::vector<std::uint8_t> unknown_regions(const Grid& g, const Params& params) {
  return unknown_regions(own_states(g, params), g.dims, params);
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  apply_voxel_rules(st, own_states(g, params), g.dims, params);
}

}  // namespace occseg
