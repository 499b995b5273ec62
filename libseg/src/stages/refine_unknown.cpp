// Stage 5, step 1 (section 3.3): unknown segments grow into free voxels at 0.5 along the six
// scan directions.
//
// The rule: along a scan, a candidate (a voxel the segmentation calls free whose own value is in
// the band, "equal to 0.5") right after an unknown voxel becomes unknown; the scan goes on from
// it, so a run of candidates after an unknown voxel becomes unknown up to the first voxel with
// another value. The scans run x+, x-, y+, y-, z+, z-, each on the result of the one before.
//
// The scans work on two bit masks, 64 voxels of a row per word: W (state unknown) and C (the
// candidates still free). Along y and z a row takes the rule from the row before it in scan
// order, 64 lanes at once: grow_from(), the rule as written. Along x the voxels of a scan follow
// each other in one row of bits; grow_up() and grow_down() fill whole runs of candidates at once
// (Refine.GrowthAlongXIsTheRuleAlongZ checks them against grow_from() on the same lines).
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/parallel.hpp"
#include "stages/create.hpp"
#include "stages/own_states.hpp"
#include "stages/refine.hpp"
#include "util/bit_rows.hpp"
#include "util/thread_scratch.hpp"

namespace occseg::detail {

namespace {

constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);

// The rule's candidates among the free voxels of a row: those whose own value is in the band
// (u: the own states' unknown bits).
void keep_candidates(word_t* c, const word_t* u, std::size_t words) {
  for (std::size_t i = 0; i < words; ++i) c[i] &= u[i];
}

// One step of a scan along y or z: a row takes the rule from the row before it in scan order
// (prev_w), in each of its 64-voxel lanes: a candidate after an unknown voxel becomes unknown.
// Returns whether anything grew.
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

static_assert(occseg::kMeanCell == 8, "a cell must be one byte of the growth's mask words");

}  // namespace

std::size_t grow_unknown_scratch_bytes(const Dims& d) {
  return 2 * d.ny * d.nz * ((d.nx + 63) / 64) * sizeof(std::uint64_t);
}

void grow_unknown(std::uint8_t* states, const std::uint8_t* own, const Dims& d, int threads, std::uint8_t* scratch,
                  std::size_t scratch_bytes, const std::uint64_t* unknown_bits, std::uint8_t* occupied_rows,
                  bool packed, const std::uint8_t* cell_states, const kernels::Table& k) {
  const kernels::RefineKernels& kr = k.refine;
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
          if (!ubits) kr.pack_equal(own + nx * r, nx, kUnknown, own_u);
          kr.pack_states(st + nx * r, nx, row_w(r), row_c(r));  // C: the free voxels, for now
          keep_candidates(row_c(r), u, words);
          if (occupied_rows) occupied_rows[r] = kr.any_occupied(st + nx * r, nx);  // in L1 now
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
    parallel_for_dynamic(rows, threads, [&](std::size_t r0, std::size_t r1) {
      for (std::size_t r = r0; r < r1; ++r)
        kr.write_cells_row(cell_states + ncx * (r % ny / 8 + ncy * (r / ny / 8)), row_w(r), nx, st + nx * r);
    });
    return;
  }
  // Back into the states, rows that grew only.
  parallel_for_dynamic(rows, threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t r = r0; r < r1; ++r)
      if (grew[r]) kr.unpack_unknown(row_w(r), nx, st + nx * r);
  });
}

}  // namespace occseg::detail
