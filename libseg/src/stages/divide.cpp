#include "stages/divide.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <tuple>

#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include "occseg/error.hpp"
#include "stages/histogram.hpp"
#include "occseg/parallel.hpp"
#include "occseg/registry.hpp"
#include "stages/texture.hpp"
#include "stages/codes.hpp"
#include "kernels/cpu_features.hpp"
#include "kernels/lane_pack.hpp"
#include "util/thread_scratch.hpp"

namespace occseg {

bool should_split(const std::vector<const std::uint32_t*>& h, std::size_t bins, double x) {
  if (h.size() < 2) return false;
  double gmax = 0, gmin = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < h.size(); ++a)
    for (std::size_t b = a + 1; b < h.size(); ++b) {
      const double g = g_statistic(h[a], h[b], bins);
      gmax = std::max(gmax, g);
      gmin = std::min(gmin, g);
    }
  if (gmax == 0) return false;  // all pairs identical: uniform texture
  if (gmin == 0) return true;   // infinite ratio
  return gmax / gmin > x;
}

namespace {

// h[i] += a[i] + b[i], then a and b cleared: the extra histograms of count_block folded back.
__attribute__((target_clones("avx2", "default")))
void fold_banks(std::uint32_t* __restrict h, std::uint32_t* __restrict a, std::uint32_t* __restrict b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    h[i] += a[i] + b[i];
    a[i] = b[i] = 0;
  }
}

// Voxels [x, end) of a row into h one by one (with Check, kNoTexture voxels not counted): the
// counting kernels' tails.
template <bool Check>
inline void count_tail(const detail::code_t* row, std::uint32_t x, std::uint32_t end, std::uint32_t* h) {
  for (; x < end; ++x)
    if (!Check || row[x] != kNoTexture) ++h[row[x]];
}

// Check = false: the block holds no kNoTexture voxel (the built-in operator writes them only on
// the map's outer faces), so its voxels are counted without testing each (with the AVX2 fold
// below, division 30.6 -> 28.3 ms on the scene on one thread).
template <bool Check>
void count_rows(const detail::code_t* codes, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h) {
  std::fill(h, h + bins, 0u);
  // Rows that are not uniform count their voxels into three interleaved histograms (x mod 3):
  // such a row is mostly one code with a few others, and one histogram chained the increments
  // of that code (each waiting for the previous store). The two extra histograms live per thread
  // and are added and cleared only when a row used them.
  thread_local detail::ThreadScratch<std::uint32_t> extra;
  if (extra.size() < 2 * bins) extra.resize(2 * bins, 0u);
  std::uint32_t* const h1 = extra.data();
  std::uint32_t* const h2 = h1 + bins;
  bool used = false;
  const std::size_t nx = dims.nx, ny = dims.ny;
  std::uint32_t* const bank[3] = {h, h1, h2};
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z) {
    std::uint32_t y = b.lo[1];
#ifdef __SSE2__
    // Two rows at a time: 16 equal codes in one add, one test (and one branch) per two rows
    // (division 9 % faster than one row at a time on the scene's 8^3 blocks).
    for (; y + 1 < b.hi[1]; y += 2) {
      const detail::code_t* r0 = codes + nx * (y + ny * z);
      const detail::code_t* r1 = r0 + nx;
      std::uint32_t x = b.lo[0];
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m128i c = _mm_set1_epi16(static_cast<short>(r0[x]));
        const __m128i e0 = _mm_cmpeq_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + x)), c);
        const __m128i e1 = _mm_cmpeq_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r1 + x)), c);
        if (_mm_movemask_epi8(_mm_and_si128(e0, e1)) == 0xFFFF) {
          if (!Check || r0[x] != kNoTexture) h[r0[x]] += 16;
          continue;
        }
        used = true;
        for (int k = 0; k < 8; ++k)
          if (!Check || r0[x + k] != kNoTexture) ++bank[k % 3][r0[x + k]];
        for (int k = 0; k < 8; ++k)
          if (!Check || r1[x + k] != kNoTexture) ++bank[(k + 1) % 3][r1[x + k]];
      }
      for (; x < b.hi[0]; ++x) {
        if (!Check || r0[x] != kNoTexture) ++h[r0[x]];
        if (!Check || r1[x] != kNoTexture) ++h[r1[x]];
      }
    }
#endif
    for (; y < b.hi[1]; ++y) {  // the last row of an odd count (every row without SSE2)
      const detail::code_t* row = codes + nx * (y + ny * z);
      std::uint32_t x = b.lo[0];
#ifdef __SSE2__
      // Eight equal codes (uniform texture: most rows of most maps) in one add.
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
        if (_mm_movemask_epi8(_mm_cmpeq_epi16(v, _mm_set1_epi16(static_cast<short>(row[x])))) == 0xFFFF) {
          if (!Check || row[x] != kNoTexture) h[row[x]] += 8;
          continue;
        }
        used = true;
        const detail::code_t* r = row + x;
        for (int k = 0; k < 8; ++k)
          if (!Check || r[k] != kNoTexture) ++bank[k % 3][r[k]];
      }
#endif
      count_tail<Check>(row, x, b.hi[0], h);
    }
  }
  if (used) fold_banks(h, h1, h2, bins);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_DIVIDE_PACKED 1
// Per-thread room for the codes a count_rows_* kernel lists (at least n of them).
std::uint16_t* code_list(std::size_t n) {
  thread_local detail::ThreadScratch<std::uint16_t> storage;
  if (storage.size() < n) storage.resize(n);
  return storage.data();
}

// The listed codes, and `same` voxels of the common one, into h (kNoTexture is not counted).
template <bool Check>
inline void add_listed(std::uint32_t* h, const std::uint16_t* list, std::size_t len, detail::code_t common,
                       std::uint64_t same) {
  for (std::size_t i = 0; i < len; ++i) ++h[list[i]];
  if (!Check || common != kNoTexture) h[common] += static_cast<std::uint32_t>(same);
}

// count_rows() without a branch per group of voxels: in each 8 voxels of a row, the block's
// `common` code is counted with one compare and a popcount, and only the other codes are packed
// to the front of a vector (lane_pack_internal.hpp) and appended to a list, counted at the end.
// On the scene the flat code (every neighbour equal) is 71 % of the voxels but only a quarter of
// the 8-voxel groups are all flat (the rest hold 3.6 distinct codes on average), so the "all
// equal?" test of count_rows() was mostly false and most voxels were counted one by one. With
// Second, voxels of a `second` code are counted by a compare too (see count_rows_compress()).
template <bool Check, bool Second>
__attribute__((target("avx2,popcnt"))) void count_rows_packed(const detail::code_t* codes, const Dims& dims,
                                                              const Block& b, std::size_t bins, std::uint32_t* h,
                                                              detail::code_t common, detail::code_t second) {
  std::fill(h, h + bins, 0u);
  std::uint16_t* const list = code_list(b.volume() + 8);
  const __m128i same_code = _mm_set1_epi16(static_cast<short>(common));
  const __m128i second_code = _mm_set1_epi16(static_cast<short>(second));
  std::uint64_t same2 = 0;
  const __m128i none = _mm_set1_epi16(static_cast<short>(kNoTexture));
  std::size_t len = 0;
  std::uint64_t same = 0;
  const std::size_t nx = dims.nx, ny = dims.ny;
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
    for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y) {
      const detail::code_t* row = codes + nx * (y + ny * z);
      std::uint32_t x = b.lo[0];
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
        const __m128i eq = _mm_cmpeq_epi16(v, same_code);
        // (second != common: no lane is in both)
        const __m128i eq2 = Second ? _mm_cmpeq_epi16(v, second_code) : _mm_setzero_si128();
        // Lanes not listed: the common code (and the second), and (Check) voxels without texture.
        const __m128i counted = Second ? _mm_or_si128(eq, eq2) : eq;
        const __m128i skip = Check ? _mm_or_si128(counted, _mm_cmpeq_epi16(v, none)) : counted;
        const unsigned e = static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(eq, eq))) & 0xFFu;
        if (Second)
          same2 += static_cast<unsigned>(__builtin_popcount(_mm_movemask_epi8(_mm_packs_epi16(eq2, eq2)) & 0xFF));
        const unsigned keep = ~static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(skip, skip))) & 0xFFu;
        same += static_cast<unsigned>(__builtin_popcount(e));
        const __m128i ctl = _mm_load_si128(reinterpret_cast<const __m128i*>(detail::kLanePack.shuffle[keep]));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(list + len), _mm_shuffle_epi8(v, ctl));
        len += static_cast<unsigned>(__builtin_popcount(keep));
      }
      count_tail<Check>(row, x, b.hi[0], h);  // blocks cut by the map's edge
    }
  add_listed<Check>(h, list, len, common, same);
  if (Second) h[second] += static_cast<std::uint32_t>(same2);
}

// count_rows_packed() for two rows at a time with AVX-512 VBMI2: 16 voxels (8 of each row) in
// one 256-bit vector, the codes other than `common` packed by one compress instruction. Voxels of
// a `second` code (Second) are counted by a compare too: the built-in operator's local maxima
// (code 0) were a quarter of the listed codes on the scene (division -0.3 ms on 2 threads).
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12 inside its own AVX-512 intrinsics
#endif
template <bool Check, bool Second>
__attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi2,popcnt"))) void count_rows_compress(
    const detail::code_t* codes, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h,
    detail::code_t common, detail::code_t second) {
  std::fill(h, h + bins, 0u);
  std::uint16_t* const list = code_list(b.volume() + 32);
  std::uint64_t same2 = 0;
  const __m512i second_code4 = _mm512_set1_epi16(static_cast<short>(second));
  const __m256i same_code = _mm256_set1_epi16(static_cast<short>(common));
  const __m256i none = _mm256_set1_epi16(static_cast<short>(kNoTexture));
  std::size_t len = 0;
  std::uint64_t same = 0;
  const std::size_t nx = dims.nx, ny = dims.ny;
  const bool eight_wide = b.hi[0] - b.lo[0] == 8;  // the division's Smin blocks inside the map
  const __m512i same_code4 = _mm512_set1_epi16(static_cast<short>(common));
  const __m512i none4 = _mm512_set1_epi16(static_cast<short>(kNoTexture));
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z) {
    std::uint32_t y = b.lo[1];
    // Rows of 8 voxels four at a time: one 512-bit compare, compress and store per 32 voxels.
    if (eight_wide)
      for (; y + 3 < b.hi[1]; y += 4) {
        const detail::code_t* r0 = codes + nx * (y + ny * z) + b.lo[0];
        __m512i v = _mm512_castsi128_si512(_mm_loadu_si128(reinterpret_cast<const __m128i*>(r0)));
        v = _mm512_inserti32x4(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + nx)), 1);
        v = _mm512_inserti32x4(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + 2 * nx)), 2);
        v = _mm512_inserti32x4(v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + 3 * nx)), 3);
        const __mmask32 eq = _mm512_cmpeq_epi16_mask(v, same_code4);
        const __mmask32 eq2 = Second ? _mm512_mask_cmpeq_epi16_mask(static_cast<__mmask32>(~eq), v, second_code4) : 0;
        const auto other = static_cast<__mmask32>(~(eq | eq2));
        const __mmask32 keep = Check ? static_cast<__mmask32>(other & _mm512_cmpneq_epi16_mask(v, none4)) : other;
        same += static_cast<unsigned>(__builtin_popcount(eq));
        if (Second) same2 += static_cast<unsigned>(__builtin_popcount(eq2));
        _mm512_storeu_si512(list + len, _mm512_maskz_compress_epi16(keep, v));
        len += static_cast<unsigned>(__builtin_popcount(keep));
      }
    for (; y + 1 < b.hi[1]; y += 2) {
      const detail::code_t* r0 = codes + nx * (y + ny * z);
      const detail::code_t* r1 = r0 + nx;
      std::uint32_t x = b.lo[0];
      for (; x + 8 <= b.hi[0]; x += 8) {
        const __m256i v = _mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(r1 + x),
                                              reinterpret_cast<const __m128i*>(r0 + x));
        const __mmask16 eq = _mm256_cmpeq_epi16_mask(v, same_code);
        const __mmask16 keep = Check ? static_cast<__mmask16>(~eq & _mm256_cmpneq_epi16_mask(v, none))
                                     : static_cast<__mmask16>(~eq);
        same += static_cast<unsigned>(__builtin_popcount(eq));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(list + len), _mm256_maskz_compress_epi16(keep, v));
        len += static_cast<unsigned>(__builtin_popcount(keep));
      }
      count_tail<Check>(r0, x, b.hi[0], h);
      count_tail<Check>(r1, x, b.hi[0], h);
    }
    for (; y < b.hi[1]; ++y) count_tail<Check>(codes + nx * (y + ny * z), b.lo[0], b.hi[0], h);  // an odd row count
  }
  add_listed<Check>(h, list, len, common, same);
  if (Second) h[second] += static_cast<std::uint32_t>(same2);
}
#pragma GCC diagnostic pop

#endif

// The counting kernels, slowest first; detail::set_texture_kernel() picks them with the texture's
// (compiler: count_rows, avx2: count_rows_packed, avx512: count_rows_compress), so tests run each.
enum class Counting { rows, packed, compress };

Counting counting_kernel() {
#ifdef OCCSEG_DIVIDE_PACKED
  const detail::TextureKernel k = detail::texture_kernel();
  if (k >= detail::TextureKernel::avx512 && cpu_has_avx512vbmi2()) return Counting::compress;
  // (Every AVX2 processor has the POPCNT the packed counting uses.)
  if (k >= detail::TextureKernel::avx2 && cpu_has_avx2()) return Counting::packed;
#endif
  return Counting::rows;
}

template <bool Check>
void count_with(Counting kernel, const detail::code_t* codes, const Dims& dims, const Block& b, std::size_t bins,
                std::uint32_t* h, detail::code_t common) {
#ifdef OCCSEG_DIVIDE_PACKED
  if (kernel != Counting::rows) {
    const std::size_t first = b.lo[0] + dims.nx * (b.lo[1] + dims.ny * std::size_t(b.lo[2]));
    if (kernel == Counting::compress) {
      if (common == kNoTexture)  // (not the built-in operator's codes)
        count_rows_compress<Check, false>(codes, dims, b, bins, h, codes[first], 0);
      else  // the built-in operator's local maxima (LBP 0, level 0) second
        count_rows_compress<Check, true>(codes, dims, b, bins, h, common, 0);
      return;
    }
    if (common == kNoTexture)
      count_rows_packed<Check, false>(codes, dims, b, bins, h, codes[first], 0);
    else
      count_rows_packed<Check, true>(codes, dims, b, bins, h, common, 0);
    return;
  }
#endif
  (void)kernel;
  (void)common;
  count_rows<Check>(codes, dims, b, bins, h);
}

std::uint64_t total(const std::uint32_t* h, std::size_t n);

// faces_only: kNoTexture voxels lie only on the map's outer faces. Returns the voxels counted
// (the block's volume inside the map: no summing of the histogram for it). `common`: the code
// most voxels are expected to have (the built-in operator's flat code), or kNoTexture for the
// block's first voxel's.
std::uint64_t count_block(Counting kernel, const detail::code_t* codes, const Dims& dims, const Block& b,
                          std::size_t bins, std::uint32_t* h, bool faces_only = false,
                          detail::code_t common = kNoTexture) {
  const bool inside = faces_only && b.lo[0] > 0 && b.lo[1] > 0 && b.lo[2] > 0 && b.hi[0] < dims.nx &&
                      b.hi[1] < dims.ny && b.hi[2] < dims.nz;
  if (inside) {
    count_with<false>(kernel, codes, dims, b, bins, h, common);
    return b.volume();
  }
  count_with<true>(kernel, codes, dims, b, bins, h, common);
  return total(h, bins);
}

}  // namespace

void count_codes(const TextureMap& texture, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h) {
  count_block(counting_kernel(), reinterpret_cast<const detail::code_t*>(texture.codes.data()), dims, b, bins, h);
}

namespace {

// k ln k for integer counts, looked up: the same expression as g_statistic()'s xlogx, so the
// values are identical; counts beyond the table (blocks above 32^3 voxels) are computed.
class XLogX {
 public:
  XLogX() : t_(kSize) {
    t_[0] = 0.0;
    for (std::size_t k = 1; k < kSize; ++k) t_[k] = static_cast<double>(k) * std::log(static_cast<double>(k));
  }
  double operator()(std::uint64_t k) const {
    if (k < kSize) return t_[k];
    const double v = static_cast<double>(k);
    return v * std::log(v);
  }

 private:
  static constexpr std::size_t kSize = std::size_t(1) << 16;
  std::vector<double> t_;
};

const XLogX& xlogx_table() {
  static const XLogX t;
  return t;
}

// One child histogram with what every pair needs precomputed: its total, its sum f ln f in bin
// order, and a bit mask of its non-empty bins. In the tree the total comes first (it decides
// whether the child takes part) and the rest only once a pair needs it (`complete`): a block that
// splits after its first pairs never needed most of its children's sums.
struct Child {
  std::uint32_t* h = nullptr;
  std::uint64_t* nz = nullptr;
  std::uint64_t n = 0;
  double cells = 0;
  bool complete = false;
};

// Sum of n counts (integers: any order gives the same total).
__attribute__((target_clones("avx2", "default")))
std::uint64_t total(const std::uint32_t* h, std::size_t n) {
  std::uint64_t s = 0;
  for (std::size_t i = 0; i < n; ++i) s += h[i];
  return s;
}

// Bit k set when counts[k] != 0, for 64 counts.
inline std::uint64_t nonzero_mask(const std::uint32_t* counts) {
  std::uint64_t m = 0;
#ifdef __SSE2__
  const __m128i zero = _mm_setzero_si128();
  for (int k = 0; k < 64; k += 16) {
    const __m128i* c = reinterpret_cast<const __m128i*>(counts + k);
    const __m128i a = _mm_packs_epi32(_mm_cmpeq_epi32(_mm_loadu_si128(c), zero),
                                      _mm_cmpeq_epi32(_mm_loadu_si128(c + 1), zero));
    const __m128i b = _mm_packs_epi32(_mm_cmpeq_epi32(_mm_loadu_si128(c + 2), zero),
                                      _mm_cmpeq_epi32(_mm_loadu_si128(c + 3), zero));
    const auto zeros = static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(a, b)));
    m |= static_cast<std::uint64_t>(~zeros & 0xFFFFu) << k;
  }
#else
  for (int k = 0; k < 64; ++k) m |= static_cast<std::uint64_t>(counts[k] != 0) << k;
#endif
  return m;
}

// The G-statistic's sums in their documented order (histogram.hpp): xl of the k-th listed value
// into lane k % 8, the lanes added as ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)). Eight
// chains of additions instead of one, and no bit search: with the values listed by a vector
// compress (below), the G-statistics took 5.1 ms on the scene where the chain along the bin masks
// took 7.1 (one thread).
inline double lane_sum(const XLogX& xl, const std::uint32_t* v, std::size_t n) {
  double l0 = 0, l1 = 0, l2 = 0, l3 = 0, l4 = 0, l5 = 0, l6 = 0, l7 = 0;
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) {
    l0 += xl(v[k]);
    l1 += xl(v[k + 1]);
    l2 += xl(v[k + 2]);
    l3 += xl(v[k + 3]);
    l4 += xl(v[k + 4]);
    l5 += xl(v[k + 5]);
    l6 += xl(v[k + 6]);
    l7 += xl(v[k + 7]);
  }
  double l[8] = {l0, l1, l2, l3, l4, l5, l6, l7};
  for (; k < n; ++k) l[k % 8] += xl(v[k]);
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

// The non-zero values of a[i] (Two: of a[i] + b[i]) for i < n, in order, into out (room for n + 16
// values); n is a multiple of 64 (histograms are padded to whole mask words with zeros). Returns
// how many. AVX-512: a compress per 16 bins; AVX2: a permute per 8, its lane indices from the
// packing table (lane_pack_internal.hpp). The scalar path lists them along the children's bin
// masks instead.
#ifdef OCCSEG_DIVIDE_PACKED
template <bool Two>
__attribute__((target("avx512f,popcnt"))) std::size_t nonzero_values_avx512(const std::uint32_t* a,
                                                                             const std::uint32_t* b, std::size_t n,
                                                                             std::uint32_t* out) {
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; i += 16) {
    __m512i v = _mm512_loadu_si512(a + i);
    if (Two) v = _mm512_add_epi32(v, _mm512_loadu_si512(b + i));
    const __mmask16 k = _mm512_test_epi32_mask(v, v);
    _mm512_storeu_si512(out + m, _mm512_maskz_compress_epi32(k, v));
    m += static_cast<unsigned>(__builtin_popcount(k));
  }
  return m;
}

template <bool Two>
__attribute__((target("avx2,popcnt"))) std::size_t nonzero_values_avx2(const std::uint32_t* a, const std::uint32_t* b,
                                                                       std::size_t n, std::uint32_t* out) {
  std::size_t m = 0;
  const __m256i zero = _mm256_setzero_si256();
  for (std::size_t i = 0; i < n; i += 8) {
    __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + i));
    if (Two) v = _mm256_add_epi32(v, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(b + i)));
    const unsigned k =
        ~static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(v, zero)))) & 0xFFu;
    // vpermd's lane indices from the 16-bit packing table: entry (2j, 2j + 1) shifted right by one
    // holds j in its low three bits, the only ones vpermd reads (unused entries 0x8080: lane 0).
    const __m128i pairs = _mm_load_si128(reinterpret_cast<const __m128i*>(detail::kLanePack.shuffle[k]));
    const __m256i idx = _mm256_cvtepu16_epi32(_mm_srli_epi16(pairs, 1));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + m), _mm256_permutevar8x32_epi32(v, idx));
    m += static_cast<unsigned>(__builtin_popcount(k));
  }
  return m;
}
#endif

// h[i] = a[i] + a[stride + i] + ... + a[7 * stride + i]: eight octant histograms (`stride` apart)
// summed in one pass, h written once (a copy and seven passes of h += were 40 % more loads and
// stores). Integer counts: any order gives the same sums.
__attribute__((target_clones("avx2", "default")))
void sum_eight(std::uint32_t* __restrict h, const std::uint32_t* __restrict a, std::size_t stride, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    h[i] = ((a[i] + a[stride + i]) + (a[2 * stride + i] + a[3 * stride + i])) +
           ((a[4 * stride + i] + a[5 * stride + i]) + (a[6 * stride + i] + a[7 * stride + i]));
}

// h[i] += a[i]: summing octant histograms (fewer than eight: blocks cut by the map's edge).
__attribute__((target_clones("avx2", "default")))
void add_counts(std::uint32_t* __restrict h, const std::uint32_t* __restrict a, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) h[i] += a[i];
}

// The octree of one top block with a histogram per node (per-thread, reused).
struct Tree {
  struct Node {
    Block b;
    std::uint32_t size;   // nominal edge
    std::uint32_t first;  // index of the first octant (octants are contiguous)
    std::uint8_t nk;      // number of octants, 0 for blocks of Smin
  };
  std::vector<Node> nodes;
  std::vector<std::uint32_t> hist;
  std::vector<std::uint64_t> masks;
  std::vector<Child> child;
  std::vector<std::uint8_t> ready;
  std::vector<std::uint32_t> order;  // Smin nodes in the order they are counted
  // Voxels counted in each node, summed up the tree: it decides whether an octant takes part
  // (none: border voxels only), and finish() recomputes it with the sums a pair needs. Summing
  // each node's 512 counts for it was 5 % of this stage's instructions.
  std::vector<std::uint64_t> total;
};

// Per-thread scratch for the children of one block (reused for every block the thread handles).
struct Scratch {
  std::vector<std::uint32_t> hist;
  std::vector<std::uint64_t> masks;
  Child kids[8];
};

struct Divider {
  const Grid& grid;
  const detail::code_t* codes;
  const Params& params;
  const XLogX& xl;
  std::size_t bins;
  std::size_t words;  // 64-bit words of a bin mask
  const Similarity* sim;  // params.similarity, or nullptr for the G-statistic computed here
  bool faces_only;        // kNoTexture codes only on the map's outer faces
  detail::code_t common;  // the flat code of the built-in operator, else kNoTexture (see count_block)
  Counting kernel;

  std::uint64_t count(const Block& b, std::uint32_t* h) const {
    return count_block(kernel, codes, grid.dims, b, bins, h, faces_only, common);
  }

  // Per-thread room for the values one sum lists.
  std::uint32_t* value_list() const {
    thread_local detail::ThreadScratch<std::uint32_t> storage;
    if (storage.size() < words * 64 + 16) storage.resize(words * 64 + 16);
    return storage.data();
  }

  // The non-zero values of a.h (b: of a.h + b.h) into out, in bin order; returns how many.
  std::size_t nonzero_values(const Child& a, const Child* b, std::uint32_t* out) const {
#ifdef OCCSEG_DIVIDE_PACKED
    if (kernel == Counting::compress)
      return b ? nonzero_values_avx512<true>(a.h, b->h, words * 64, out)
               : nonzero_values_avx512<false>(a.h, nullptr, words * 64, out);
    if (kernel == Counting::packed)
      return b ? nonzero_values_avx2<true>(a.h, b->h, words * 64, out)
               : nonzero_values_avx2<false>(a.h, nullptr, words * 64, out);
#endif
    std::size_t m = 0;
    for (std::size_t w = 0; w < words; ++w)
      for (std::uint64_t u = b ? a.nz[w] | b->nz[w] : a.nz[w]; u; u &= u - 1) {
        const std::size_t i = w * 64 + static_cast<std::size_t>(__builtin_ctzll(u));
        out[m++] = b ? a.h[i] + b->h[i] : a.h[i];
      }
    return m;
  }

  // Total and sum f ln f (documented order) of the histogram c.h; the scalar path's bin mask.
  void finish(Child& c) const {
    c.complete = true;
    if (kernel == Counting::rows)
      for (std::size_t w = 0; w < words; ++w) c.nz[w] = nonzero_mask(c.h + w * 64);
    std::uint32_t* const v = value_list();
    const std::size_t m = nonzero_values(c, nullptr, v);
    std::uint64_t n = 0;
    for (std::size_t k = 0; k < m; ++k) n += v[k];
    c.n = n;
    c.cells = lane_sum(xl, v, m);
  }

  void histogram(const Block& b, Child& c) const {
    count(b, c.h);
    finish(c);
  }

  // g_statistic(a.h, b.h, bins), bit for bit: the same terms in the same order, with the
  // per-histogram sums taken from the children and the joint term summed over the union of
  // their non-empty bins (the bins where both are empty have no term).
  double g(const Child& a, const Child& b) const {
    std::uint32_t* const v = value_list();
    const double joint = lane_sum(xl, v, nonzero_values(a, &b, v));
    const double ns = static_cast<double>(a.n), nm = static_cast<double>(b.n);
    const double cells = a.cells + b.cells;
    const double g = 2.0 * (cells - xl(a.n) - xl(b.n) - joint + xl(a.n + b.n));
    return g > 1e-9 * (ns + nm) ? g : 0.0;
  }

  // should_split() over the non-empty children. With the G-statistic (never negative) the answer
  // is known as soon as the pairs seen so far say "split": more pairs can only raise Gmax and lower
  // Gmin, so a ratio above X (or Gmin = 0 < Gmax) stays so. Most examined blocks of a real map do
  // split, usually after two or three of their 28 pairs, and the pairs were most of this stage.
  // A plugin similarity may be negative, so it gets every pair.
  bool split(Child* const* used, std::size_t n) const {
    if (n < 2) return false;
    double gmax = 0, gmin = std::numeric_limits<double>::infinity();
    auto ready = [&](Child& c) -> const Child& {
      if (!c.complete) finish(c);
      return c;
    };
    // Pairs in the order (0,1), (0,2), (1,2), (0,3), ...: every pair of the first children before
    // the next child, so that a block that splits after p pairs needed about sqrt(2p) + 1 children
    // finished instead of p + 1. Gmax and Gmin over all pairs do not depend on the order.
    for (std::size_t b = 1; b < n; ++b)
      for (std::size_t a = 0; a < b; ++a) {
        const double v = sim ? compare_histograms(*sim, used[a]->h, used[b]->h, bins) : g(ready(*used[a]), ready(*used[b]));
        gmax = std::max(gmax, v);
        gmin = std::min(gmin, v);
        if (!sim && gmax > 0 && (gmin == 0 || gmax / gmin > params.split_ratio)) return true;
      }
    if (gmax == 0) return false;
    if (gmin == 0) return true;
    return gmax / gmin > params.split_ratio;
  }

  // Octants of a block of nominal edge `size` whose low corner is a multiple of `size`.
  static int octants(const Block& b, std::uint32_t size, Block* out) {
    const std::uint32_t half = size / 2;
    int n = 0;
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
      if (!empty) out[n++] = c;
    }
    return n;
  }

  void run(const Block& b, std::uint32_t size, std::vector<Block>& leaves, Scratch& s) const {
    if (size <= static_cast<std::uint32_t>(params.smin)) {
      leaves.push_back(b);
      return;
    }
    Block kids[8];
    const int nk = octants(b, size, kids);
    if (nk == 1) {  // the map edge left a single octant: nothing to compare yet
      run(kids[0], size / 2, leaves, s);
      return;
    }
    Child* used[8] = {};  // the first nu are set (GCC cannot tell and warns)
    std::size_t nu = 0;
    for (int k = 0; k < nk; ++k) {
      histogram(kids[k], s.kids[k]);
      if (s.kids[k].n) used[nu++] = &s.kids[k];  // octants of border voxels only carry no texture
    }
    if (!split(used, nu)) {
      leaves.push_back(b);
      return;
    }
    for (int k = 0; k < nk; ++k) run(kids[k], size / 2, leaves, s);  // scratch is free again here
  }

  // ---- The same recursion with every histogram of a top block's octree computed up front:
  // codes counted once, in the Smin blocks, and each larger block's histogram summed from its
  // octants' (the top-down recursion above counts a voxel again at every level it examines).

  // Worth it when the tree's histograms fit in a few MB and a bottom block holds at least a
  // quarter as many voxels as there are bins (otherwise summing would cost more than counting).
  bool use_tree() const {
    const std::uint64_t ratio = static_cast<std::uint64_t>(params.smax / params.smin);
    const std::uint64_t smin3 = static_cast<std::uint64_t>(params.smin) * params.smin * params.smin;
    return !sim && ratio * ratio * ratio * words * 64 <= (std::uint64_t(1) << 20) && words * 64 <= 4 * smin3;
  }

  void build(Tree& t, const Block& top, std::uint32_t size) const {
    t.nodes.clear();
    t.nodes.push_back({top, size, 0, 0});
    for (std::size_t i = 0; i < t.nodes.size(); ++i) {  // breadth first: octants are contiguous
      const Tree::Node nd = t.nodes[i];
      if (nd.size <= static_cast<std::uint32_t>(params.smin)) continue;
      Block kids[8];
      const int nk = octants(nd.b, nd.size, kids);
      t.nodes[i].first = static_cast<std::uint32_t>(t.nodes.size());
      t.nodes[i].nk = static_cast<std::uint8_t>(nk);
      for (int k = 0; k < nk; ++k) t.nodes.push_back({kids[k], nd.size / 2, 0, 0});
    }
    const std::size_t stride = words * 64, nn = t.nodes.size();
    if (t.hist.size() < nn * stride) t.hist.resize(nn * stride);
    if (t.masks.size() < nn * words) t.masks.resize(nn * words);
    t.child.assign(nn, Child());
    t.ready.assign(nn, 0);
    // The Smin blocks first, in scan order of their corners: x-neighbours then share the cache
    // lines of their 8-code rows (four blocks per line), where the tree's order jumped between
    // octants and planes.
    t.order.clear();
    for (std::size_t i = 1; i < nn; ++i)
      if (t.nodes[i].nk == 0) t.order.push_back(static_cast<std::uint32_t>(i));
    std::sort(t.order.begin(), t.order.end(), [&](std::uint32_t a, std::uint32_t b) {
      const Block &p = t.nodes[a].b, &q = t.nodes[b].b;
      return std::tie(p.lo[2], p.lo[1], p.lo[0]) < std::tie(q.lo[2], q.lo[1], q.lo[0]);
    });
    t.total.assign(nn, 0);
    // While counting a block, one of the eight planes of the block eight places on (the next row
    // of blocks across the top block, when it is eight blocks wide) is prefetched, across the top
    // block's width: over eight blocks, the next row of blocks arrives whole. The hardware
    // prefetchers did not follow the jumps from row to row and plane to plane (counting 8.5 ->
    // 7.1 ms on the scene, one thread); all of a row of blocks at once (192 prefetches) gained
    // nothing.
    const std::size_t nx = grid.dims.nx, ny = grid.dims.ny;
    const std::size_t row_bytes = (top.hi[0] - top.lo[0]) * sizeof(detail::code_t);
    for (std::size_t j = 0; j < t.order.size(); ++j) {
      if (j + 8 < t.order.size()) {
        const Block& ahead = t.nodes[t.order[j + 8]].b;
        const std::size_t z = ahead.lo[2] + j % 8;
        if (z < ahead.hi[2])
          for (std::size_t y = ahead.lo[1]; y < ahead.hi[1]; ++y) {
            const char* r = reinterpret_cast<const char*>(codes + nx * (y + ny * z) + top.lo[0]);
            for (std::size_t q = 0; q < row_bytes; q += 64) __builtin_prefetch(r + q);
            __builtin_prefetch(r + row_bytes - 1);
          }
      }
      const std::uint32_t i = t.order[j];
      t.total[i] = count(t.nodes[i].b, t.hist.data() + i * stride);
    }
    for (std::size_t i = nn; i-- > 1;) {  // octants after their parent: bottom up
      const Tree::Node& nd = t.nodes[i];
      if (nd.nk == 0) continue;
      std::uint32_t* h = t.hist.data() + i * stride;
      const std::uint32_t* first = t.hist.data() + std::size_t(nd.first) * stride;
      if (nd.nk == 8) {
        sum_eight(h, first, stride, bins);
      } else {
        std::copy(first, first + bins, h);
        for (int k = 1; k < nd.nk; ++k) add_counts(h, first + k * stride, bins);
      }
      for (int k = 0; k < nd.nk; ++k) t.total[i] += t.total[nd.first + static_cast<std::size_t>(k)];
    }
  }

  Child& child(Tree& t, std::size_t i) const {
    Child& c = t.child[i];
    if (!t.ready[i]) {
      c.h = t.hist.data() + i * words * 64;
      c.nz = t.masks.data() + i * words;
      c.n = t.total[i];
      c.complete = false;
      t.ready[i] = 1;
    }
    return c;
  }

  void run_tree(Tree& t, std::size_t i, std::vector<Block>& leaves) const {
    const Tree::Node nd = t.nodes[i];
    if (nd.size <= static_cast<std::uint32_t>(params.smin)) {
      leaves.push_back(nd.b);
      return;
    }
    if (nd.nk == 1) {
      run_tree(t, nd.first, leaves);
      return;
    }
    Child* used[8] = {};  // the first nu are set (GCC cannot tell and warns)
    std::size_t nu = 0;
    for (int k = 0; k < nd.nk; ++k) {
      Child& c = child(t, nd.first + static_cast<std::size_t>(k));
      if (c.n) used[nu++] = &c;
    }
    if (!split(used, nu)) {
      leaves.push_back(nd.b);
      return;
    }
    for (int k = 0; k < nd.nk; ++k) run_tree(t, nd.first + static_cast<std::size_t>(k), leaves);
  }
};

}  // namespace

std::vector<Block> divide(const Grid& grid, const TextureMap& tex, const Params& params) {
  return detail::divide_codes(grid, reinterpret_cast<const detail::code_t*>(tex.codes.data()), tex.code_count(), params,
                              false);
}

std::vector<Block> detail::divide_codes(const Grid& grid, const code_t* codes, int code_count, const Params& params,
                                        bool faces_only) {
  const std::uint32_t s = static_cast<std::uint32_t>(params.smax);
  const std::size_t n[3] = {grid.dims.nx, grid.dims.ny, grid.dims.nz};
  std::size_t t[3];
  for (int a = 0; a < 3; ++a) t[a] = (n[a] + s - 1) / s;
  const std::size_t tops = t[0] * t[1] * t[2];
  std::vector<std::vector<Block>> per_top(tops);
  const std::size_t bins = static_cast<std::size_t>(code_count);
  // The built-in operator's flat code: LBP 63 (no neighbour below the centre), contrast level 0.
  const auto flat = static_cast<code_t>(faces_only ? bins / 64 * 63 : kNoTexture);
  const Divider d{grid, codes, params, xlogx_table(), bins, (bins + 63) / 64, division_similarity(params),
                  faces_only, flat, counting_kernel()};
  const bool tree_path = d.use_tree();
  // Threads take top blocks one at a time from a shared counter: they differ a lot in cost
  // (uniform ones never split), and fixed shares left one thread idle for a quarter of the stage.
  // Each top block's leaves go to its own list, so the result does not depend on who took it.
  const std::size_t workers = std::min<std::size_t>(tops, static_cast<std::size_t>(resolve_threads(params.threads)));
  std::atomic<std::size_t> next{0};
  parallel_for(workers, params.threads, [&](std::size_t, std::size_t) {
    Tree tree;
    Scratch sc;
    sc.hist.assign(8 * d.words * 64, 0);
    sc.masks.assign(8 * d.words, 0);
    for (int k = 0; k < 8; ++k) {
      sc.kids[k].h = sc.hist.data() + k * d.words * 64;
      sc.kids[k].nz = sc.masks.data() + k * d.words;
    }
    for (std::size_t i; (i = next.fetch_add(1, std::memory_order_relaxed)) < tops;) {
      const std::size_t c[3] = {i % t[0], (i / t[0]) % t[1], i / (t[0] * t[1])};
      Block blk;
      for (int a = 0; a < 3; ++a) {
        blk.lo[a] = static_cast<std::uint32_t>(c[a] * s);
        blk.hi[a] = static_cast<std::uint32_t>(std::min<std::size_t>(n[a], (c[a] + 1) * s));
      }
      if (tree_path) {
        d.build(tree, blk, s);
        d.run_tree(tree, 0, per_top[i]);
      } else {
        d.run(blk, s, per_top[i], sc);
      }
    }
  });
  std::vector<Block> leaves;
  for (auto& v : per_top) leaves.insert(leaves.end(), v.begin(), v.end());
  return leaves;
}

}  // namespace occseg
