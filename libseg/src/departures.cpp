#include "occseg/departures.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <mutex>

#include "occseg/parallel.hpp"
#include "bit_rows_internal.hpp"
#include "cpu_features.hpp"
#include "huge_pages.hpp"
#include "own_states_internal.hpp"
#include "occseg/refine.hpp"

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

// in[x + k] of a bit row (k in [1, 63]), with `out_bit` for positions past the row.
inline std::uint64_t from_right(const word_t* a, std::size_t W, std::size_t i, unsigned k, std::uint64_t pad,
                                std::uint64_t out_word) {
  const std::uint64_t cur = i + 1 == W ? a[i] | pad : a[i];
  const std::uint64_t next = i + 1 < W ? (i + 2 == W ? a[i + 1] | pad : a[i + 1]) : out_word;
  return (cur >> k) | (next << (64 - k));
}
// in[x - k] of a bit row (k in [1, 63]), with `out_word` bits for positions before the row.
inline std::uint64_t from_left(const word_t* a, std::size_t i, unsigned k, std::uint64_t out_word) {
  const std::uint64_t prev = i > 0 ? a[i - 1] : out_word;
  return (a[i] << k) | (prev >> (64 - k));
}

// One axis of a box erosion (AND; the outside counts as 1) or dilation (OR; the outside counts as
// 0) of radius r, from `in` to `out`: the same windows, clipped by the map, as the byte version it
// replaced (docs/performance.md). Along x, rows [r0, r1).
void box_x(const BitMask& in, BitMask& out, std::size_t r0, std::size_t r1, int r, bool erode) {
  const std::size_t W = in.W;
  const std::uint64_t tail = in.tail();
  // Erosion: the bits past nx count as 1 while shifting, then go back to 0.
  const std::uint64_t pad = erode ? ~tail : 0, outside = erode ? ~std::uint64_t(0) : 0;
  for (std::size_t rw = r0; rw < r1; ++rw) {
    const word_t* a = in.row(rw);
    word_t* o = out.row(rw);
    for (std::size_t i = 0; i < W; ++i) {
      std::uint64_t v = a[i];
      for (int k = 1; k <= r && std::size_t(k) < in.nx; ++k) {
        // Radii of 64 or more never occur (gap_radius <= 16), so k < 64 here.
        const std::uint64_t rt = from_right(a, W, i, static_cast<unsigned>(k), pad, outside);
        const std::uint64_t lt = from_left(a, i, static_cast<unsigned>(k), outside);
        v = erode ? (v & rt & lt) : (v | rt | lt);
      }
      o[i] = i + 1 == W ? v & tail : v;
    }
  }
}

// Along y (the rows of plane z: step 1, len ny, first row z * ny) or z (the rows of slice y:
// step ny, len nz, first row y): row k of the line takes the rows up to r away along it.
void box_line(const BitMask& in, BitMask& out, std::size_t first, std::size_t step, std::size_t len, std::size_t k,
              int r, bool erode) {
  const std::size_t W = in.W, R = static_cast<std::size_t>(r);
  word_t* o = out.row(first + k * step);
  const std::size_t lo = k >= R ? k - R : 0, hi = std::min(len - 1, k + R);
  const word_t* a0 = in.row(first + lo * step);
  std::copy(a0, a0 + W, o);
  for (std::size_t j = lo + 1; j <= hi; ++j) {
    const word_t* a = in.row(first + j * step);
    if (erode)
      for (std::size_t i = 0; i < W; ++i) o[i] &= a[i];
    else
      for (std::size_t i = 0; i < W; ++i) o[i] |= a[i];
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

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_RULES_AVX2 1
__attribute__((target("avx2"))) inline __m256i at32(const std::uint8_t* p, std::size_t x) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + x));
}

// rule() on voxels x .. x + 31 of a row, in place; returns the seeds of the gap flood among them
// (0xFF: a gap voxel left unknown with an occupied neighbour, as rules_row()'s callers check).
__attribute__((target("avx2"))) inline __m256i rules_step_avx2(std::uint8_t* st, const std::uint8_t* own,
                                                               const word_t* region, const std::uint8_t* ym,
                                                               const std::uint8_t* yp, const std::uint8_t* zm,
                                                               const std::uint8_t* zp, std::size_t x) {
  const __m256i occ = _mm256_set1_epi8(static_cast<char>(kOccupied)), unk = _mm256_set1_epi8(static_cast<char>(kUnknown));
  const __m256i fre = _mm256_set1_epi8(static_cast<char>(kFree));
  const __m256i o = at32(own, x), s = at32(st, x);
  const __m256i touches =
      _mm256_or_si256(_mm256_or_si256(_mm256_cmpeq_epi8(at32(own, x - 1), occ), _mm256_cmpeq_epi8(at32(own, x + 1), occ)),
                      _mm256_or_si256(_mm256_or_si256(_mm256_cmpeq_epi8(at32(ym, x), occ), _mm256_cmpeq_epi8(at32(yp, x), occ)),
                                      _mm256_or_si256(_mm256_cmpeq_epi8(at32(zm, x), occ), _mm256_cmpeq_epi8(at32(zp, x), occ))));
  const __m256i reg = detail::bytes_of_bits32(region, x);
  const __m256i gap = _mm256_blendv_epi8(s, unk, _mm256_and_si256(_mm256_cmpeq_epi8(s, fre), touches));
  const __m256i own_unknown = _mm256_cmpeq_epi8(o, unk);
  const __m256i res = _mm256_blendv_epi8(o, _mm256_blendv_epi8(gap, unk, reg), own_unknown);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(st + x), res);
  return _mm256_andnot_si256(reg, _mm256_and_si256(_mm256_and_si256(own_unknown, touches), _mm256_cmpeq_epi8(res, unk)));
}

// rules_row() for rows of at least 34 voxels, 32 voxels per step in hand-written AVX2, with the
// region read from its bit row (no byte row unpacked first); the last step overlaps the one
// before instead of a scalar tail (the rules are idempotent: a second application to a result
// gives the result). GCC's vectorised rules_row spent two thirds of its instructions on a row of
// 320 in its scalar tails and second pass. The seeds of the gap flood come out of the same
// steps, exactly (`first` + x for each, appended to `seeds` in x order): rules_row()'s superset
// sent most rows of the scene through a scalar search (0.6 of the rules' 2.2 ms).
__attribute__((target("avx2"))) void rules_row_avx2(std::uint8_t* st, const std::uint8_t* own, const word_t* region,
                                                    const std::uint8_t* ym, const std::uint8_t* yp,
                                                    const std::uint8_t* zm, const std::uint8_t* zp, std::size_t n,
                                                    std::size_t first, std::vector<std::size_t>& seeds) {
  const auto reg_at = [&](std::size_t i) { return static_cast<std::uint8_t>((region[i / 64] >> (i % 64)) & 1); };
  auto across = [&](std::size_t i) {
    return (ym[i] == kOccupied) | (yp[i] == kOccupied) | (zm[i] == kOccupied) | (zp[i] == kOccupied);
  };
  const bool t0 = (own[1] == kOccupied) | across(0), tn = (own[n - 2] == kOccupied) | across(n - 1);
  auto seed = [&](std::size_t i, bool t) {
    return (own[i] == kUnknown) & (reg_at(i) == 0) & t & (st[i] == kUnknown);
  };
  // voxel x of the step at x0 is a seed where bit x - x0 of m is set; bits below `from` - x0 are
  // voxels an earlier step reported already
  const auto add = [&](std::size_t x0, std::uint32_t m, std::size_t from) {
    if (from > x0) m &= ~0u << (from - x0);
    for (; m; m &= m - 1) seeds.push_back(first + x0 + static_cast<std::size_t>(__builtin_ctz(m)));
  };
  st[0] = rule(st[0], own[0], reg_at(0), t0);
  if (seed(0, t0)) seeds.push_back(first);
  std::size_t x = 1;
  for (; x + 32 <= n - 1; x += 32)
    add(x, static_cast<std::uint32_t>(_mm256_movemask_epi8(rules_step_avx2(st, own, region, ym, yp, zm, zp, x))), x);
  if (x < n - 1)
    add(n - 1 - 32, static_cast<std::uint32_t>(_mm256_movemask_epi8(rules_step_avx2(st, own, region, ym, yp, zm, zp, n - 1 - 32))), x);
  st[n - 1] = rule(st[n - 1], own[n - 1], reg_at(n - 1), tn);
  if (seed(n - 1, tn)) seeds.push_back(first + n - 1);
}
#endif

std::atomic<bool> g_vector_rules{true};

}  // namespace

namespace detail {
void set_vector_rules(bool enabled) { g_vector_rules.store(enabled, std::memory_order_relaxed); }
}  // namespace detail

namespace {

// Rule 2's regions as a bit mask (a row of bits per row of voxels; bit set: the voxel is at 0.5
// and in a region). apply_voxel_rules() reads it row by row; the byte mask of unknown_regions()
// is made from it only when asked for: allocating, zero-filling and writing 13 MB of bytes, and
// reading them back, cost more than the opening itself.
BitMask region_bits(const std::uint8_t* own, const Dims& d, const Params& params, std::uint8_t* scratch = nullptr,
                    std::size_t scratch_bytes = 0, const std::uint64_t* unknown_bits = nullptr) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, rows = ny * nz, bytes = BitMask::bytes(nx, rows);
  const int r = params.gap_radius;
  // Three masks in the scratch when it holds them (not for very narrow maps: a word per row).
  const bool fits = scratch && 3 * bytes <= scratch_bytes;
  BitMask a(nx, rows, fits ? scratch : nullptr), b(nx, r > 0 ? rows : 0, fits ? scratch + bytes : nullptr),
      c(nx, r > 0 ? rows : 0, fits ? scratch + 2 * bytes : nullptr);
  // The 0.5 bits from the texture's pass (CellRows) when there are, else packed from own here.
  const BitMask half(nx, unknown_bits ? rows : 0, const_cast<std::uint64_t*>(unknown_bits));
  if (r <= 0) {  // no opening: every 0.5 voxel is in a region
    parallel_for_dynamic(rows, params.threads, [&](std::size_t r0, std::size_t r1) {
      for (std::size_t rw = r0; rw < r1; ++rw) {
        if (unknown_bits) std::copy(half.row(rw), half.row(rw) + a.W, a.row(rw));
        else detail::pack_equal(own + rw * nx, nx, kUnknown, a.row(rw));
      }
    });
    return a;
  }
  // Opening = erosion then dilation, each three axis passes in the order x, y, z. The x and y
  // passes stay inside a plane of fixed z, so they run plane by plane right after what they read
  // (three parallel loops and in-cache planes instead of six loops over the whole mask):
  //   per plane: 0.5 bits -> a, erode x a -> b, erode y b -> a;
  //   per plane: erode z a -> b, dilate x b -> c, dilate y c -> b;
  //   per plane: dilate z b -> c.
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z) {
      if (unknown_bits) {
        box_x(half, b, ny * z, ny * (z + 1), r, true);
      } else {
        for (std::size_t y = 0; y < ny; ++y) detail::pack_equal(own + (y + ny * z) * nx, nx, kUnknown, a.row(y + ny * z));
        box_x(a, b, ny * z, ny * (z + 1), r, true);
      }
      for (std::size_t y = 0; y < ny; ++y) box_line(b, a, ny * z, 1, ny, y, r, true);
    }
  });
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z) {
      for (std::size_t y = 0; y < ny; ++y) box_line(a, b, y, ny, nz, z, r, true);
      box_x(b, c, ny * z, ny * (z + 1), r, false);
      for (std::size_t y = 0; y < ny; ++y) box_line(c, b, ny * z, 1, ny, y, r, false);
    }
  });
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) box_line(b, c, y, ny, nz, z, r, false);
  });
  return c;
}

inline bool bit(const BitMask& m, std::size_t row, std::size_t x) { return (m.row(row)[x / 64] >> (x % 64)) & 1u; }

}  // namespace

std::vector<std::uint8_t> unknown_regions(const std::vector<std::uint8_t>& own, const Dims& d, const Params& params) {
  const BitMask a = region_bits(own.data(), d, params);
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
void flood_gaps_from_objects(std::uint8_t* st, const std::uint8_t* own,
                             const BitMask& region, const Dims& d, std::vector<std::size_t>& queue) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sz = nx * ny;
  auto gap = [&](std::size_t i) { return own[i] == kUnknown && !bit(region, i / nx, i % nx); };
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

void detail::apply_voxel_rules(std::uint8_t* st, const std::uint8_t* own, const Dims& d,
                               const Params& params, std::uint8_t* scratch, std::size_t scratch_bytes,
                               const std::uint64_t* unknown_bits) {
  const BitMask region = region_bits(own, d, params, scratch, scratch_bytes, unknown_bits);
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sz = nx * ny;
  const std::vector<std::uint8_t> none(nx, kFree);  // outside the map: no occupied neighbour
  // Reads only own states and each voxel's own entry of st, so rows are independent. The seeds of
  // the gap flood are gathered on the way, slab by slab (the AVX2 rows find them exactly; the
  // others flag rows that may hold some, which are then searched).
  std::vector<std::size_t> seeds;
  std::mutex seeds_mutex;
#ifdef OCCSEG_RULES_AVX2
  const bool avx2 = nx >= 34 && cpu_has_avx2() && g_vector_rules.load(std::memory_order_relaxed);
#endif
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::size_t> mine;
    std::vector<std::uint8_t> reg(nx);  // this row's region bits as bytes
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t i = nx * (y + ny * z);
        const std::uint8_t* o = own + i;
        const word_t* const bits = region.row(y + ny * z);
        const std::uint8_t *ym = y > 0 ? o - nx : none.data(), *yp = y + 1 < ny ? o + nx : none.data();
        const std::uint8_t *zm = z > 0 ? o - sz : none.data(), *zp = z + 1 < nz ? o + sz : none.data();
#ifdef OCCSEG_RULES_AVX2
        if (avx2) {
          rules_row_avx2(st + i, o, bits, ym, yp, zm, zp, nx, i, mine);
          continue;
        }
#endif
        unpack_half(bits, o, nx, reg.data());
        if (!rules_row(st + i, o, reg.data(), ym, yp, zm, zp, nx)) continue;
        for (std::size_t x = 0; x < nx; ++x) {
          const std::size_t j = i + x;
          // (the region bit alone: it matters only where the own state is unknown)
          if (st[j] != kUnknown || own[j] != kUnknown || ((bits[x / 64] >> (x % 64)) & 1)) continue;
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

void apply_voxel_rules(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                       const Params& params) {
  detail::apply_voxel_rules(st.data(), own.data(), d, params, nullptr, 0);
}

std::vector<std::uint8_t> unknown_regions(const Grid& g, const Params& params) {
  return unknown_regions(own_states(g, params), g.dims, params);
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  apply_voxel_rules(st, own_states(g, params), g.dims, params);
}

}  // namespace occseg
