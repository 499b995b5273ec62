// The `default` preset's per-voxel rules (rules 1-3 of docs/algorithm.md, "Presets"), applied
// after refinement: rule 2's unknown regions by a morphological opening of the 0.5 voxels, the
// rules on every voxel (rules/voxel_rules.hpp, through the table's rules_row kernel), and rule 3's
// flood through the gaps connected to an object.
#include "rules/departures.hpp"

#include <algorithm>
#include <cstdint>
#include <mutex>

#include "occseg/parallel.hpp"
#include "rules/voxel_rules.hpp"
#include "stages/own_states.hpp"
#include "stages/refine.hpp"
#include "util/bit_rows.hpp"
#include "util/huge_pages.hpp"

namespace occseg {

namespace {

using rules::kFree;
using rules::kUnknown;

// The opening works on bit masks, 64 voxels of a row per word: its six passes then stream 1/8 of
// the memory byte masks would. Row r of the mask is words [r * W, (r + 1) * W), W = ceil(nx / 64),
// voxel x at bit x % 64 of word x / 64; the bits past nx in a row's last word are kept 0
// (util/bit_rows.hpp). The words live in the mask's own vector, or in scratch storage handed in
// (segment() gives part of the label array, which then holds no labels yet); every row is written
// before it is read, so that storage is not cleared.
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
// 0) of radius r, from `in` to `out`: windows of 2r + 1 voxels clipped by the map. Along x, rows
// [r0, r1). Each word is shifted against the words before and after it, which the loop carries
// along in registers (not reloaded, with a test for the row's ends, at every shift).
template <bool Erode, unsigned Fixed>
void box_x_rows(const BitMask& in, BitMask& out, std::size_t r0, std::size_t r1, int r) {
  const std::size_t W = in.W;
  const std::uint64_t tail = in.tail();
  // Erosion: the bits past nx count as 1 while shifting, then go back to 0.
  const std::uint64_t pad = Erode ? ~tail : 0, outside = Erode ? ~std::uint64_t(0) : 0;
  // Radii of 64 or more never occur (gap_radius <= 16), so k < 64. (Fixed: the radius known when
  // compiling, for the default's 1.)
  const unsigned K =
      Fixed ? Fixed : static_cast<unsigned>(std::min<std::size_t>(static_cast<std::size_t>(r), in.nx - 1));
  for (std::size_t rw = r0; rw < r1; ++rw) {
    const word_t* a = in.row(rw);
    word_t* o = out.row(rw);
    // An empty row stays empty (erosion too: its bits past nx never reach a voxel's bit alone),
    // and is most of the rows of a mask of regions.
    std::uint64_t any = 0;
    for (std::size_t i = 0; i < W; ++i) any |= a[i];
    if (!any) {
      for (std::size_t i = 0; i < W; ++i) o[i] = 0;
      continue;
    }
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
  // (r = 1 with nx = 1 is K = 0 at run time: the general loop.)
  const bool one = r == 1 && in.nx > 1;
  if (erode) one ? box_x_rows<true, 1>(in, out, r0, r1, r) : box_x_rows<true, 0>(in, out, r0, r1, r);
  else one ? box_x_rows<false, 1>(in, out, r0, r1, r) : box_x_rows<false, 0>(in, out, r0, r1, r);
}

// One axis of the box erosion or dilation along y, for every row of one plane (ny rows of W
// words, contiguous; `in` and `out` apart): row y of out takes rows y - r .. y + r of in, clipped
// by the plane (the same windows as box_x's, and as the z pass's over planes).
void box_y_plane(const word_t* in, word_t* out, std::size_t ny, std::size_t W, int r, bool erode) {
  const std::size_t P = ny * W;
  if (r == 1 && ny >= 2) {  // the default: one pass, rows y - 1, y, y + 1 at once (no copy first)
    const auto op = [erode](std::uint64_t a, std::uint64_t b) { return erode ? a & b : a | b; };
    for (std::size_t i = 0; i < W; ++i) out[i] = op(in[i], in[i + W]);
    if (erode)
      for (std::size_t i = W; i + W < P; ++i) out[i] = in[i - W] & in[i] & in[i + W];
    else
      for (std::size_t i = W; i + W < P; ++i) out[i] = in[i - W] | in[i] | in[i + W];
    for (std::size_t i = P - W; i < P; ++i) out[i] = op(in[i - W], in[i]);
    return;
  }
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

}  // namespace

namespace {

// Rule 2's regions as a bit mask (a row of bits per row of voxels; bit set: the voxel is at 0.5
// and in a region). apply_voxel_rules() reads it row by row; the byte mask of unknown_regions()
// is made from it only when asked for: allocating, zero-filling, writing and reading back a byte
// per voxel costs more than the opening itself.
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
  // x and y (Exy) and those fully eroded and dilated in x and y (Dxy) in rings of its own, small
  // enough to stay in L1 and L2, instead of three passes over whole masks with two waits for all
  // threads. Per plane z:
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
      if (b == a + 2) {  // three planes (the default's r = 1 inside the map): one pass, no copy
        const word_t *p1 = ring(v, a + 1).w, *p2 = ring(v, a + 2).w;
        if (erode)
          for (std::size_t i = 0; i < P; ++i) to.w[i] = first[i] & p1[i] & p2[i];
        else
          for (std::size_t i = 0; i < P; ++i) to.w[i] = first[i] | p1[i] | p2[i];
        return;
      }
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

std::vector<std::uint8_t> unknown_regions(const std::vector<std::uint8_t>& own, const Dims& d, const Params& params,
                                          const kernels::Table& k) {
  const detail::OwnBitsStore bits = detail::pack_own_bits(own.data(), d, params.threads);
  const BitMask a = region_bits(bits.bits, d, params);
  std::vector<std::uint8_t> m;
  resize_huge(m, own.size());
  const std::size_t nx = d.nx;
  parallel_for_dynamic(a.rows, params.threads, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t rw = r0; rw < r1; ++rw)
      k.rules.unpack_half(a.row(rw), own.data() + rw * nx, nx, m.data() + rw * nx);
  });
  return m;
}

namespace {

// Rule 3 carried through whole gaps: every gap voxel the texture calls free that is 6-connected,
// through gap voxels, to a gap voxel touching an occupied voxel becomes unknown. The unobserved
// inside of a thin structure (a table top seen only edge-on) is such a gap; without this it would
// be labelled free everywhere but along its rim. `queue` holds the seeds (gap voxels left unknown
// that touch an occupied voxel), in any order: the result is a set (connected components), so it
// does not depend on visiting order. On more threads the map is cut into slabs of planes, each
// flooded by one thread, which alone writes its voxels (states, masks, row kinds); a step into
// another slab is handed to that slab's next round, until no round hands anything on.
// With `sf`, `su` (the state masks, writable) and `kinds` (their row kinds), the voxels made
// unknown move from the free mask to the unknown one.
void flood_gaps_from_objects(std::uint8_t* st, const detail::OwnBits& own, const BitMask& region, const Dims& d,
                             std::vector<std::size_t>& queue, int threads, word_t* sf = nullptr, word_t* su = nullptr,
                             std::uint8_t* kinds = nullptr) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sz = nx * ny;
  const auto workers = static_cast<std::size_t>(resolve_threads(threads));
  const std::size_t slabs = std::min<std::size_t>(nz, queue.size() < 4096 || workers < 2 ? 1 : 4 * workers);
  const auto first_plane = [&](std::size_t s) { return s * nz / slabs; };  // slab s: planes [first(s), first(s + 1))
  const auto slab_of = [&](std::size_t i) {
    const std::size_t z = i / sz;
    std::size_t s = z * slabs / nz;  // (within one of the slab, either way)
    while (s + 1 < slabs && first_plane(s + 1) <= z) ++s;
    while (first_plane(s) > z) --s;
    return s;
  };
  // inbox[s]: voxels of slab s to take if they are free gap voxels, then flood from; the seeds
  // are flooded from as they are.
  std::vector<std::vector<std::size_t>> inbox(slabs), seeds(slabs);
  for (const std::size_t i : queue) seeds[slab_of(i)].push_back(i);
  queue = std::vector<std::size_t>();
  // What slab s hands to the slab below it (s - 1) and above it (s + 1) this round.
  std::vector<std::vector<std::size_t>> to_below(slabs), to_above(slabs);
  for (bool first = true;; first = false) {
    parallel_for_dynamic(slabs, threads, [&](std::size_t s0, std::size_t s1) {
      for (std::size_t s = s0; s < s1; ++s) {
        std::vector<std::size_t> stack = first ? std::move(seeds[s]) : std::vector<std::size_t>();
        const auto take = [&](std::size_t j) {
          if (st[j] != kFree || !(own.at(j / nx, j % nx) == kUnknown && !bit(region, j / nx, j % nx))) return;
          st[j] = kUnknown;
          if (sf) {
            const std::size_t row = j / nx, x = j % nx, w = row * own.words + x / 64;
            sf[w] &= ~(std::uint64_t(1) << (x % 64));
            su[w] |= std::uint64_t(1) << (x % 64);
            kinds[row] |= detail::StateBits::kUnknown;  // (kFree may stay: a superset)
          }
          stack.push_back(j);
        };
        for (const std::size_t j : inbox[s]) take(j);
        // (Steps along x and y stay in the plane, so in the slab; along z they may leave it.)
        const std::size_t z0 = first_plane(s), z1 = first_plane(s + 1);
        while (!stack.empty()) {
          const std::size_t i = stack.back();
          stack.pop_back();
          const std::size_t x = i % nx, y = (i / nx) % ny, z = i / sz;
          if (x > 0) take(i - 1);
          if (x + 1 < nx) take(i + 1);
          if (y > 0) take(i - nx);
          if (y + 1 < ny) take(i + nx);
          if (z > 0) {
            if (z > z0)
              take(i - sz);
            else
              to_below[s].push_back(i - sz);
          }
          if (z + 1 < nz) {
            if (z + 1 < z1)
              take(i + sz);
            else
              to_above[s].push_back(i + sz);
          }
        }
      }
    });
    bool more = false;
    for (std::size_t s = 0; s < slabs; ++s) {
      inbox[s].clear();
      if (s > 0) inbox[s].insert(inbox[s].end(), to_above[s - 1].begin(), to_above[s - 1].end());
      if (s + 1 < slabs) inbox[s].insert(inbox[s].end(), to_below[s + 1].begin(), to_below[s + 1].end());
      more = more || !inbox[s].empty();
    }
    for (std::size_t s = 0; s < slabs; ++s) to_below[s].clear(), to_above[s].clear();
    if (!more) break;
  }
}

}  // namespace

void detail::apply_voxel_rules(std::uint8_t* st, const OwnBits& own, const Dims& d, const Params& params,
                               std::uint8_t* scratch, std::size_t scratch_bytes, const kernels::Table& k,
                               StateBits* bits, std::uint64_t* bit_storage, std::uint8_t* row_kinds) {
  const BitMask region = region_bits(own, d, params, scratch, scratch_bytes);
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, W = own.words, n = ny * nz * W;
  word_t* const sf = bits ? reinterpret_cast<word_t*>(bit_storage) : nullptr;
  word_t* const su = bits ? sf + n : nullptr;
  word_t* const so = bits ? sf + 2 * n : nullptr;
  const std::vector<std::uint64_t> none(W, 0);  // outside the map: no occupied neighbour
  // Reads only own states and each voxel's own entry of st, so rows are independent. The seeds of
  // the gap flood are gathered on the way, slab by slab.
  std::vector<std::size_t> seeds;
  std::mutex seeds_mutex;
  const kernels::RulesKernels& kr = k.rules;
  parallel_for_dynamic(nz, params.threads, [&](std::size_t z0, std::size_t z1) {
    std::vector<std::size_t> mine;
    std::vector<std::uint64_t> touching(W);
    const word_t* const t = reinterpret_cast<const word_t*>(touching.data());
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t r = y + ny * z, i = nx * r;
        const auto* const u = reinterpret_cast<const word_t*>(own.unknown) + r * W;
        const auto* const o = reinterpret_cast<const word_t*>(own.occupied) + r * W;
        const auto* const out = reinterpret_cast<const word_t*>(none.data());
        // The touching bits matter only for voxels at 0.5 (rule 3): a row without one skips them.
        std::uint64_t any_half = 0;
        for (std::size_t w = 0; w < W; ++w) any_half |= u[w];
        if (any_half)
          touching_bits(o, y > 0 ? o - W : out, y + 1 < ny ? o + W : out, z > 0 ? o - ny * W : out,
                        z + 1 < nz ? o + ny * W : out, W, touching.data());
        if (sf) {
          kr.rules_row(st + i, u, o, region.row(r), t, nx, i, mine, sf + r * W, su + r * W, so + r * W);
          row_kinds[r] = detail::row_kinds(sf + r * W, su + r * W, so + r * W, W);
        } else {
          kr.rules_row(st + i, u, o, region.row(r), t, nx, i, mine, nullptr, nullptr, nullptr);
        }
      }
    std::lock_guard<std::mutex> lock(seeds_mutex);
    seeds.insert(seeds.end(), mine.begin(), mine.end());
  });
  flood_gaps_from_objects(st, own, region, d, seeds, params.threads, sf, su, row_kinds);
  if (bits) *bits = StateBits{sf, su, so, W, row_kinds};
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                       const Params& params, const kernels::Table& k) {
  const detail::OwnBitsStore bits = detail::pack_own_bits(own.data(), d, params.threads);
  detail::apply_voxel_rules(st.data(), bits.bits, d, params, nullptr, 0, k);
}

std::vector<std::uint8_t> unknown_regions(const Grid& g, const Params& params, const kernels::Table& k) {
  return unknown_regions(own_states(g, params), g.dims, params, k);
}

void apply_voxel_rules(std::vector<std::uint8_t>& st, const Grid& g, const Params& params, const kernels::Table& k) {
  apply_voxel_rules(st, own_states(g, params), g.dims, params, k);
}

}  // namespace occseg
