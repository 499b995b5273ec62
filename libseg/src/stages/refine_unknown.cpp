// The unknown growth of the refinement (section 3.3's scans for unknown voxels) on bit masks.
//
// The six scans only ever turn "candidates" (voxels the texture calls free whose own value is in
// the band, own state unknown) into unknown voxels, along each line in scan order: x+, x-, y+, y-,
// z+, z-. Two bits per voxel say all there is: W (state unknown) and C (candidate), 64 voxels of
// a row per word. Along x a scan fills each run of candidates next to an unknown voxel (an
// addition carries through the run, or a search finds its start); along y and z a row takes
// W[k] |= W[k-1] & C[k] from the row before it, 64 lanes at once. The byte scans this replaces
// tested every row and direction on three rows of bytes (the row before, the row, its own
// states) before scanning it: 5.5 of the scene's 13.5 ms of refinement, 2.6 now
// (docs/performance.md, "Fifth round").
#include <algorithm>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include "stages/create.hpp"
#include "occseg/parallel.hpp"
#include "stages/texture.hpp"
#include "util/bit_rows.hpp"
#include "kernels/cpu_features.hpp"
#include "stages/own_states.hpp"
#include "util/thread_scratch.hpp"

namespace occseg::detail {

namespace {

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_GROWTH_AVX2 1
#endif

// W and C of one row from the states and the bits of the own states' unknown voxels (u): C is
// "free" and u. (bits past nx stay 0: u's are 0.)
void pack_row_bits(const std::uint8_t* st, const word_t* u, std::size_t nx, word_t* w, word_t* c) {
  const std::size_t words = (nx + 63) / 64;
  std::fill(w, w + words, 0);
  std::fill(c, c + words, 0);
  std::size_t x = 0;
#ifdef __SSE2__
  const __m128i unknown = _mm_set1_epi8(static_cast<char>(kUnknown)), free = _mm_set1_epi8(static_cast<char>(kFree));
  for (; x + 16 <= nx; x += 16) {
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(st + x));
    set_bits16(w, x, _mm_cmpeq_epi8(s, unknown));
    set_bits16(c, x, _mm_cmpeq_epi8(s, free));
  }
#endif
  for (; x < nx; ++x) {
    w[x / 64] |= static_cast<std::uint64_t>(st[x] == kUnknown) << (x % 64);
    c[x / 64] |= static_cast<std::uint64_t>(st[x] == kFree) << (x % 64);
  }
  for (std::size_t i = 0; i < words; ++i) c[i] &= u[i];
}

#ifdef OCCSEG_GROWTH_AVX2
// pack_row_bits() 32 voxels per step (self-contained: a call into the baseline SSE2 code from
// here made the growth twice as slow).
__attribute__((target("avx2"))) void pack_row_bits_avx2(const std::uint8_t* st, const word_t* u, std::size_t nx,
                                                        word_t* w, word_t* c) {
  const std::size_t words = (nx + 63) / 64;
  std::fill(w, w + words, 0);
  std::fill(c, c + words, 0);
  const __m256i unknown = _mm256_set1_epi8(static_cast<char>(kUnknown)), free = _mm256_set1_epi8(static_cast<char>(kFree));
  std::size_t x = 0;
  for (; x + 32 <= nx; x += 32) {
    const __m256i s = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(st + x));
    set_bits32(w, x, _mm256_cmpeq_epi8(s, unknown));
    set_bits32(c, x, _mm256_cmpeq_epi8(s, free));
  }
  for (; x < nx; ++x) {
    w[x / 64] |= static_cast<std::uint64_t>(st[x] == kUnknown) << (x % 64);
    c[x / 64] |= static_cast<std::uint64_t>(st[x] == kFree) << (x % 64);
  }
  for (std::size_t i = 0; i < words; ++i) c[i] &= u[i];
}
#endif

// st[x] = unknown where bit x of w is set (a grown candidate, or a voxel unknown already).
void unpack_row(const word_t* w, std::size_t nx, std::uint8_t* st) {
  std::size_t x = 0;
#ifdef __SSE2__
  const __m128i unknown = _mm_set1_epi8(static_cast<char>(kUnknown));
  for (; x + 16 <= nx; x += 16) {
    const __m128i set = bytes_of_bits16(w, x);
    __m128i* p = reinterpret_cast<__m128i*>(st + x);
    _mm_storeu_si128(p, _mm_or_si128(_mm_and_si128(set, unknown), _mm_andnot_si128(set, _mm_loadu_si128(p))));
  }
#endif
  for (; x < nx; ++x)
    if ((w[x / 64] >> (x % 64)) & 1u) st[x] = kUnknown;
}

// Scan x+ of one row: each run of candidates that starts right after an unknown voxel becomes
// unknown. A seed (the run's first voxel) added to the run carries through it: (C + S) ^ C holds
// the run and the bit past it. The seeds come from W as it was (a voxel made unknown here ends
// up inside a run that is filled anyway; as a seed it would be added twice). Returns whether
// anything grew.
bool grow_up(word_t* w, word_t* c, std::size_t words) {
  std::uint64_t before_top = 0, carry = 0, grown = 0;  // W's bit 63 of the word before, as it was
  for (std::size_t i = 0; i < words; ++i) {
    const std::uint64_t cw = c[i], ww = w[i];
    const std::uint64_t seed = cw & ((ww << 1) | before_top);
    before_top = ww >> 63;
    const std::uint64_t a = cw + seed, sum = a + carry;
    carry = static_cast<std::uint64_t>(a < cw) | static_cast<std::uint64_t>(sum < a);
    const std::uint64_t fill = (sum ^ cw) & cw;
    w[i] = ww | fill;
    c[i] = cw & ~fill;
    grown |= fill;
  }
  return grown != 0;
}

// Scan x- of one row: each run of candidates that ends right before an unknown voxel becomes
// unknown, from the run's last voxel (a seed) down to its first (the highest non-candidate
// below it, plus one). A run that reaches bit 0 goes on in the word below: its bit 63 is then a
// seed, next to the bit 0 just made unknown.
bool grow_down(word_t* w, word_t* c, std::size_t words) {
  bool grown = false;
  for (std::size_t i = words; i-- > 0;) {
    std::uint64_t seed = c[i] & ((w[i] >> 1) | (i + 1 < words ? w[i + 1] << 63 : 0));
    while (seed) {
      const int k = 63 - __builtin_clzll(seed);
      const std::uint64_t below = k == 63 ? ~std::uint64_t(0) : (std::uint64_t(2) << k) - 1;  // bits 0..k
      const std::uint64_t gaps = ~c[i] & below;
      const int j = gaps ? 64 - __builtin_clzll(gaps) : 0;  // the run's lowest bit in this word
      const std::uint64_t fill = below & (~std::uint64_t(0) << j);
      w[i] |= fill;
      c[i] &= ~fill;
      seed &= ~fill;
      grown = true;
    }
  }
  return grown;
}

// One step of a scan along y or z: row `cur` takes the unknown voxels of the row before it in
// scan order, 64 lanes at once.
bool grow_from(const word_t* prev_w, word_t* w, word_t* c, std::size_t words) {
  std::uint64_t grown = 0;
  for (std::size_t i = 0; i < words; ++i) {
    const std::uint64_t g = prev_w[i] & c[i];
    w[i] |= g;
    c[i] &= ~g;
    grown |= g;
  }
  return grown != 0;
}

// Byte i of the result 0xFF where bit i of b (i < 8) is set, else 0.
inline std::uint64_t spread_bits(std::uint64_t b) {
  const std::uint64_t x = (b * 0x0101010101010101ull) & 0x8040201008040201ull;  // byte i: bit i
  return (((x | (x + 0x7F7F7F7F7F7F7F7Full)) & 0x8080808080808080ull) >> 7) * 0xFF;
}

// Voxels [x0, nx) of a row (x0 a multiple of 8) from its cells' states cs (kMeanCell = 8 voxels
// each) and its bits w (the growth's unknown voxels, every voxel of an unknown cell among them):
// unknown where w has a bit, the cell's state elsewhere.
static_assert(occseg::kMeanCell == 8, "a cell must be one byte of the growth's mask words");
void write_row(const std::uint8_t* cs, const word_t* w, std::size_t x0, std::size_t nx, std::uint8_t* st) {
  std::size_t cx = x0 / 8;
  for (; (cx + 1) * 8 <= nx; ++cx) {
    const std::uint64_t unknown = spread_bits((w[cx / 8] >> (8 * (cx % 8))) & 0xFF);
    const std::uint64_t v = ((0x0101010101010101ull * cs[cx]) & ~unknown) | (0x0101010101010101ull * kUnknown & unknown);
    std::memcpy(st + 8 * cx, &v, 8);
  }
  for (std::size_t x = 8 * cx; x < nx; ++x) st[x] = ((w[x / 64] >> (x % 64)) & 1u) ? kUnknown : cs[cx];
}

#ifdef OCCSEG_GROWTH_AVX2
// write_row() 32 voxels (4 cells, read as one 4-byte word: all in the row) per step.
__attribute__((target("avx2"))) void write_row_avx2(const std::uint8_t* cs, const word_t* w, std::size_t nx,
                                                    std::uint8_t* st) {
  // byte i of a 128-bit half takes cell i / 8 of the four (the low half cells 0, 1; the high 2, 3)
  const __m256i pick = _mm256_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3,
                                        3, 3, 3, 3, 3, 3);
  const __m256i unknown = _mm256_set1_epi8(static_cast<char>(kUnknown));
  std::size_t x = 0;
  for (; x + 32 <= nx; x += 32) {
    std::uint32_t four;
    std::memcpy(&four, cs + x / 8, 4);
    const __m256i cells = _mm256_shuffle_epi8(_mm256_set1_epi32(static_cast<int>(four)), pick);
    const __m256i v = _mm256_blendv_epi8(cells, unknown, bytes_of_bits32(w, x));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(st + x), v);
  }
  write_row(cs, w, x, nx, st);
}
#endif

}  // namespace

std::size_t grow_unknown_scratch_bytes(const Dims& d) {
  return 2 * d.ny * d.nz * ((d.nx + 63) / 64) * sizeof(std::uint64_t);
}

void grow_unknown(std::uint8_t* states, const std::uint8_t* own, const Dims& d, int threads,
                  std::uint8_t* scratch, std::size_t scratch_bytes, const std::uint64_t* unknown_bits,
                  std::uint8_t* occupied_rows, bool packed, const std::uint8_t* cell_states) {
  const word_t* const ubits = reinterpret_cast<const word_t*>(unknown_bits);
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, rows = ny * nz, words = (nx + 63) / 64;
  std::vector<std::uint64_t> own_words;
  word_t* masks;
  if (scratch && scratch_bytes >= grow_unknown_scratch_bytes(d)) {
    masks = reinterpret_cast<word_t*>(scratch);
  } else {
    packed = false;  // (the creation writes them only where they fit)
    own_words.resize(2 * rows * words);
    masks = reinterpret_cast<word_t*>(own_words.data());
  }
  word_t* const W = masks;                  // row r at W + r * words
  word_t* const C = masks + rows * words;
  std::vector<std::uint8_t> grew(rows, 0);  // rows whose W changed: the only ones written back
  std::uint8_t* const st = states;
  auto row_w = [&](std::size_t r) { return W + r * words; };
  auto row_c = [&](std::size_t r) { return C + r * words; };

  // x and y, plane by plane (z fixed): the lines of both lie in the plane.
#ifdef OCCSEG_GROWTH_AVX2
  const bool avx2 = cpu_has_avx2();
#endif
  parallel_for_dynamic(nz, threads, [&](std::size_t z0, std::size_t z1) {
    ThreadScratch<std::uint64_t> own_words(ubits || packed ? 0 : words);
    word_t* const own_u = reinterpret_cast<word_t*>(own_words.data());
    for (std::size_t z = z0; z < z1; ++z) {
      const std::size_t r0 = ny * z;
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t r = r0 + y;
        if (!packed) {
          // The own states' unknown voxels as bits: handed in (own is not read), or packed here.
          const word_t* u = ubits ? ubits + words * r : own_u;
          if (!ubits) pack_equal(own + nx * r, nx, kUnknown, own_u);
#ifdef OCCSEG_GROWTH_AVX2
          if (avx2) pack_row_bits_avx2(st + nx * r, u, nx, row_w(r), row_c(r));
          else
#endif
            pack_row_bits(st + nx * r, u, nx, row_w(r), row_c(r));
          if (occupied_rows) occupied_rows[r] = any_occupied(st + nx * r, nx);  // in L1 now
        }
        bool g = grow_up(row_w(r), row_c(r), words);
        g = grow_down(row_w(r), row_c(r), words) || g;
        grew[r] = g;
      }
      for (std::size_t y = 1; y < ny; ++y)
        if (grow_from(row_w(r0 + y - 1), row_w(r0 + y), row_c(r0 + y), words)) grew[r0 + y] = 1;
      for (std::size_t y = ny - 1; y-- > 0;)
        if (grow_from(row_w(r0 + y + 1), row_w(r0 + y), row_c(r0 + y), words)) grew[r0 + y] = 1;
    }
  });
  // z, slice by slice (y fixed).
  parallel_for_dynamic(ny, threads, [&](std::size_t y0, std::size_t y1) {
    for (std::size_t y = y0; y < y1; ++y) {
      for (std::size_t z = 1; z < nz; ++z)
        if (grow_from(row_w(y + ny * (z - 1)), row_w(y + ny * z), row_c(y + ny * z), words)) grew[y + ny * z] = 1;
      for (std::size_t z = nz - 1; z-- > 0;)
        if (grow_from(row_w(y + ny * (z + 1)), row_w(y + ny * z), row_c(y + ny * z), words)) grew[y + ny * z] = 1;
    }
  });
  if (cell_states && packed) {  // every row, written once (the creation left them)
    const std::size_t ncx = (nx + 7) / 8, ncy = (ny + 7) / 8;
#ifdef OCCSEG_GROWTH_AVX2
    // (following set_texture_kernel(), so that the tests run both)
    const bool avx2_rows = avx2 && texture_kernel() >= TextureKernel::avx2;
#endif
    parallel_for_dynamic(rows, threads, [&](std::size_t r0, std::size_t r1) {
      for (std::size_t r = r0; r < r1; ++r) {
        const std::uint8_t* cs = cell_states + ncx * (r % ny / 8 + ncy * (r / ny / 8));
#ifdef OCCSEG_GROWTH_AVX2
        if (avx2_rows) write_row_avx2(cs, row_w(r), nx, st + nx * r);
        else
#endif
          write_row(cs, row_w(r), 0, nx, st + nx * r);
      }
    });
    return;
  }
  // Back into the states, rows that grew only.
  parallel_for_dynamic(rows, threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r)
      if (grew[r]) unpack_row(row_w(r), nx, st + nx * r);
  });
}

}  // namespace occseg::detail
