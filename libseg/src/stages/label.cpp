#include "stages/label.hpp"

#include <algorithm>
#include <functional>
#include <cstring>
#include <limits>
#include <mutex>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "stages/texture.hpp"
#include "kernels/cpu_features.hpp"
#include "util/huge_pages.hpp"
#include "pipeline/segment_internal.hpp"
#include "util/thread_scratch.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace occseg {

namespace {

// Union-find whose roots are always the smallest index of their set, so that numbering roots in
// index order numbers sets by their first element.
inline std::uint32_t find(std::uint32_t* parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

inline void unite(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
  a = find(parent, a);
  b = find(parent, b);
  if (a == b) return;
  if (a < b) std::swap(a, b);
  parent[a] = b;
}

// find() and unite() for several threads uniting in one forest at once (the slab join): a root
// becomes a child only by a compare-and-swap from itself, and every entry only ever moves to a
// smaller index of its own set, so the sets and their roots (their smallest index) come out the
// same whatever the threads' interleaving.
inline std::uint32_t find_shared(std::uint32_t* parent, std::uint32_t i) {
  while (true) {
    const std::uint32_t p = __atomic_load_n(&parent[i], __ATOMIC_RELAXED);
    if (p == i) return i;
    const std::uint32_t g = __atomic_load_n(&parent[p], __ATOMIC_RELAXED);
    if (g != p) __atomic_store_n(&parent[i], g, __ATOMIC_RELAXED);  // halving: g is an ancestor of i too
    i = g;
  }
}

inline void unite_shared(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
  while (true) {
    a = find_shared(parent, a);
    b = find_shared(parent, b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    std::uint32_t expected = a;  // a is still a root: hang it under b
    if (__atomic_compare_exchange_n(&parent[a], &expected, b, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) return;
  }
}

// First x in [x, e) with (s[x] == v) == want, or e. 16 voxels per step where SSE2 exists
// (every x86-64): runs of one state are long in real maps.
inline std::size_t find_first(const std::uint8_t* s, std::uint8_t v, bool want, std::size_t x, std::size_t e) {
#ifdef __SSE2__
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  while (x + 16 <= e) {
    unsigned m = static_cast<unsigned>(_mm_movemask_epi8(
        _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x)), vv)));
    if (!want) m = ~m & 0xFFFFu;
    if (m) return x + static_cast<std::size_t>(__builtin_ctz(m));
    x += 16;
  }
#endif
  while (x < e && (s[x] == v) != want) ++x;
  return x;
}

// End of the run of equal states that starts at x in row `s` of length nx.
inline std::size_t run_end(const std::uint8_t* s, std::size_t x, std::size_t nx) {
  return find_first(s, s[x], false, x + 1, nx);
}

// First x of the run of equal states that holds voxel x of row `s` (searching back from x).
inline std::size_t run_start(const std::uint8_t* s, std::size_t x) {
  const std::uint8_t v = s[x];
#ifdef __SSE2__
  const __m128i vv = _mm_set1_epi8(static_cast<char>(v));
  while (x >= 16) {  // voxels [x - 16, x)
    const auto m = static_cast<unsigned>(_mm_movemask_epi8(
                       _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x - 16)), vv))) ^
                   0xFFFFu;
    if (m) return x - 16 + static_cast<std::size_t>(32 - __builtin_clz(m));  // past the last other state
    x -= 16;
  }
#endif
  while (x > 0 && s[x - 1] == v) --x;
  return x;
}

// Calls fn(j) for the first voxel j of every run of state v in row `other` that meets [lo, hi):
// one call per run (a run is one component), the first one's start found by searching back.
template <typename Fn>
inline void for_each_run_in(const std::uint8_t* other, std::uint8_t v, std::size_t lo, std::size_t hi, Fn&& fn) {
  std::size_t x = find_first(other, v, true, lo, hi);
  if (x == hi) return;
  if (x == lo) x = run_start(other, x);
  while (true) {
    fn(x);
    x = find_first(other, v, false, std::max(x + 1, lo), hi);
    x = find_first(other, v, true, x, hi);
    if (x == hi) return;
  }
}

// Calls fn(slab) for every slab, through parallel_for_dynamic: slabs differ widely in cost (on the
// noisy benchmark map the lower half took 30 ms per slab, the upper 1 ms), so fixed halves left
// one thread idle. Each slab's work only writes its own data, so the order changes nothing.
template <typename Fn>
void for_each_slab(std::size_t slabs, int threads, Fn&& fn) {
  parallel_for_dynamic(slabs, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t sl = b; sl < e; ++sl) fn(sl);
  });
}

constexpr std::uint8_t kOccupiedState = static_cast<std::uint8_t>(State::occupied);

struct SlotStats {  // one segment's share of one slab
  std::uint32_t id;
  std::uint64_t voxels = 0;
  double mop = 0;
  std::uint32_t lo[3], hi[3];
  std::uint64_t sum[3] = {0, 0, 0};
};

// Run starts as bits (voxel i at bit i % 8 of byte i / 8): the statistics pass finds its runs
// there once the states are gone (1/8 byte per voxel; the states are 1). Slabs are a multiple of
// 8 voxels long, so each slab writes only bytes of its own.
static_assert(kLabelSlab % 8 == 0, "slabs must start on a byte of the run-start bits");

// First set bit in [i, end) of `bits` (padded by 8 bytes past its last byte), or end.
inline std::size_t next_start(const std::uint8_t* bits, std::size_t i, std::size_t end) {
  while (i < end) {
    std::uint64_t w;
    std::memcpy(&w, bits + i / 8, sizeof w);  // little-endian: bit i % 8 of byte i / 8 is bit i % 8
    w >>= i % 8;
    if (w) return std::min(end, i + static_cast<std::size_t>(__builtin_ctzll(w)));
    i += 64 - i % 8;
  }
  return end;
}

// Set bits of `bits` in [b, e). With b a row's first voxel and e a run start: the run's index in
// its row (the slab join looks the dense slabs' runs up by it; at most a row per call).
inline std::size_t starts_between(const std::uint8_t* bits, std::size_t b, std::size_t e) {
  std::size_t c = 0;
  for (; b < e && b % 8; ++b) c += (bits[b / 8] >> (b % 8)) & 1u;
  for (; b + 8 <= e; b += 8) c += static_cast<std::size_t>(__builtin_popcount(bits[b / 8]));
  for (; b < e; ++b) c += (bits[b / 8] >> (b % 8)) & 1u;
  return c;
}

// next_start() reading no byte past the one of voxel end - 1: while the slabs are being
// labelled, the bytes after a slab's are the next slab's (slabs start on a byte).
inline std::size_t next_start_in(const std::uint8_t* bits, std::size_t i, std::size_t end) {
  const std::size_t last = (end + 7) / 8;  // bytes [0, last) may be read
  while (i < end) {
    std::uint64_t w = 0;
    const std::size_t at = i / 8;
    if (at + sizeof w <= last) std::memcpy(&w, bits + at, sizeof w);  // little-endian, as in next_start
    else std::memcpy(&w, bits + at, last - at);
    w >>= i % 8;
    if (w) return std::min(end, i + static_cast<std::size_t>(__builtin_ctzll(w)));
    i += 64 - i % 8;
  }
  return end;
}

// The sum of a run's values v[0, n) (a run: a maximal stretch of one segment along x), the
// documented order of the mean occupancy (components.hpp): voxel k adds to lane k % 8 in turn,
// the lanes are added as ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)). Eight chains of
// dependent additions instead of one: one chain through the map cost a quarter of the labelling.
// SSE2 (every x86-64) adds two lanes per instruction, with the same roundings.
inline double run_sum(const float* v, std::size_t n) {
  double l[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  std::size_t k = 0;
#ifdef __SSE2__
  if (n >= 8) {
    __m128d a = _mm_setzero_pd(), b = a, c = a, d = a;  // lanes 0-1, 2-3, 4-5, 6-7
    for (; k + 8 <= n; k += 8) {
      const __m128 lo = _mm_loadu_ps(v + k), hi = _mm_loadu_ps(v + k + 4);
      a = _mm_add_pd(a, _mm_cvtps_pd(lo));
      b = _mm_add_pd(b, _mm_cvtps_pd(_mm_movehl_ps(lo, lo)));
      c = _mm_add_pd(c, _mm_cvtps_pd(hi));
      d = _mm_add_pd(d, _mm_cvtps_pd(_mm_movehl_ps(hi, hi)));
    }
    _mm_storeu_pd(l, a);
    _mm_storeu_pd(l + 2, b);
    _mm_storeu_pd(l + 4, c);
    _mm_storeu_pd(l + 6, d);
  }
#endif
  for (; k < n; ++k) l[k & 7] += v[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

#if defined(__x86_64__) && defined(__GNUC__)
#pragma GCC diagnostic push
#ifndef __clang__  // (a GCC warning inside its own AVX-512 intrinsics; Clang does not know it)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// run_sum() with the eight lanes in one AVX-512 register: one conversion and one addition per
// eight voxels instead of twelve SSE2 instructions, the same additions in the same order.
__attribute__((target("avx512f"))) double run_sum_avx512(const float* v, std::size_t n) {
  __m512d acc = _mm512_setzero_pd();
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) acc = _mm512_add_pd(acc, _mm512_cvtps_pd(_mm256_loadu_ps(v + k)));
  double l[8];
  _mm512_storeu_pd(l, acc);
  for (; k < n; ++k) l[k & 7] += v[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}
#pragma GCC diagnostic pop
#endif

// Runs (maximal stretches of one state along x) in every `every`-th of `rows` consecutive rows of
// nx states. (The differences are summed with SSE2's sum of absolute differences: baseline x86-64
// has no popcount instruction, and the library call for it cost 1.5 ms on the scene.)
inline std::size_t count_runs(const std::uint8_t* s, std::size_t rows, std::size_t nx, std::size_t every) {
  std::size_t runs = 0;
  for (std::size_t r = 0; r < rows; r += every) {
    const std::uint8_t* row = s + r * nx;
    runs += 1;
    std::size_t x = 1;
#ifdef __SSE2__
    const __m128i one = _mm_set1_epi8(1), zero = _mm_setzero_si128();
    __m128i acc = zero;
    for (; x + 16 <= nx; x += 16) {  // voxels x .. x + 15 against the ones before them
      const __m128i same = _mm_cmpeq_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x)),
                                          _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x - 1)));
      acc = _mm_add_epi64(acc, _mm_sad_epu8(_mm_andnot_si128(same, one), zero));
    }
    runs += static_cast<std::size_t>(_mm_cvtsi128_si64(acc)) +
            static_cast<std::size_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(acc, acc)));
#endif
    for (; x < nx; ++x) runs += row[x] != row[x - 1];
  }
  return runs;
}

// label_components() on states `s`; `release`, when given, frees the states as soon as the
// components are known (before the statistics pass).
//
// The label array is written once, with the final labels: until then only the entry of each
// run's first voxel is used (a run: a maximal stretch of one state along x within a row, which
// lies in one component), as its union-find parent, then as its slab-local component number.
// Filling every voxel's entry in the first two passes moved 200 MB more on a 320 x 320 x 128 map.
void label_states(const std::uint8_t* s, const std::function<void()>& release, const Grid& g,
                  LabelArray& labels, std::vector<Segment>& segments, int threads, bool occupied26,
                  std::vector<std::uint8_t>& starts) {
  const std::size_t n = g.dims.count();
  detail::check_labels_fit(n);
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, nz = g.dims.nz, sz = nx * ny;
  const std::size_t slabs = (nz + kLabelSlab - 1) / kLabelSlab;
  resize_huge(labels, n);
  std::uint32_t* lab = labels.data();
  const float* p = g.p.data();
  starts.assign(n / 8 + 9, 0);  // run starts, for the statistics pass (storage kept if large enough)

  // 1. Each slab on its own: runs along x, united with the runs they touch in the rows before
  // them in y and z (inside the slab), then numbered 0..m-1 by first voxel. Two ways, the same
  // result:
  // - dense (slabs whose runs are 32 voxels long or more on average, such as the scene's): the
  //   slab's runs in a table (start, state, union-find parent by the runs' dense indices). A few
  //   thousand entries per slab of the scene stay in L1, where parents at the run starts in the
  //   label array (3.2 MB per slab) missed L2 at nearly every step; the runs of two rows meet
  //   where their x ranges overlap, and both rows' runs are sorted by x, so a merge-like walk
  //   finds every pair without reading the states of the row before (labelling 11.8 -> 10.8 ms).
  // - sparse (shorter runs: noisy maps): the parents at the run starts in the label array, which
  //   the label array holds anyway; a table of short runs (9 bytes each) raised the noisy map's
  //   peak from 5.8 to 6.3 bytes per voxel. Tables of runs 32 voxels long on average take 0.3
  //   byte per voxel of a slab, of the one or two slabs each thread has at a time.
  std::vector<std::uint32_t> local_count(slabs, 0);
  std::vector<std::vector<std::uint8_t>> local_state(slabs);  // state of each local component
  // The dense slabs' runs, kept for the join and the statistics: the first run of each row
  // (row_first) and each run's local number in scan order (run_local); empty for sparse slabs,
  // whose numbers are at their run starts in the label array. The dense slabs write no label
  // before the statistics: their numbers at the run starts cost a read and a write of a line of
  // the label array every two runs or so.
  std::vector<std::vector<std::uint32_t>> row_first(slabs), run_local(slabs);
  const auto sparse = [&](std::size_t sl) __attribute__((noinline)) {
    const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
    for (std::size_t z = zb; z < ze; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t i0 = nx * (y + ny * z);
        const std::uint8_t* row = s + i0;
        for (std::size_t x = 0; x < nx;) {
          const std::size_t e = run_end(row, x, nx);
          const auto rs = static_cast<std::uint32_t>(i0 + x);
          lab[rs] = rs;
          starts[rs / 8] = static_cast<std::uint8_t>(starts[rs / 8] | (1u << (rs % 8)));
          const std::uint8_t v = row[x];
          auto with = [&](std::size_t other0) {  // unites with the run starting at other0 + j
            return [&, other0](std::size_t j) { unite(lab, rs, static_cast<std::uint32_t>(other0 + j)); };
          };
          if (occupied26 && v == kOccupiedState) {
            // Neighbours before this run in scan order: row y-1 of this plane and rows y-1..y+1
            // of the plane below, each one voxel wider on both sides.
            const std::size_t lo = x > 0 ? x - 1 : 0, hi = std::min(nx, e + 1);
            if (y > 0) for_each_run_in(row - nx, v, lo, hi, with(i0 - nx));
            if (z > zb)
              for (std::size_t yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < ny; ++yy) {
                const std::size_t j0 = nx * (yy + ny * (z - 1));
                for_each_run_in(s + j0, v, lo, hi, with(j0));
              }
          } else {
            if (y > 0) for_each_run_in(row - nx, v, x, e, with(i0 - nx));
            if (z > zb) for_each_run_in(row - sz, v, x, e, with(i0 - sz));
          }
          x = e;
        }
      }
    // Local numbering: a run start's parent is a smaller run start of the slab, already
    // renumbered (the parent entries are being overwritten in index order). The run starts are
    // found in their bits, not by scanning the states again.
    std::uint32_t m = 0;
    const std::size_t end = ze * sz;
    for (std::size_t rs = next_start_in(starts.data(), zb * sz, end); rs < end;
         rs = next_start_in(starts.data(), rs + 1, end)) {
      const std::uint32_t par = lab[rs];
      if (par == rs) local_state[sl].push_back(s[rs]);
      lab[rs] = par == rs ? m++ : lab[par];
    }
    local_count[sl] = m;
  };
  const auto dense = [&](std::size_t sl) __attribute__((noinline)) {
    const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab), rows = (ze - zb) * ny;
    std::vector<std::uint32_t> first(rows + 1);  // row r's runs: [first[r], first[r + 1])
    std::vector<std::uint32_t> rx, par;          // per run: start x, union-find parent
    std::vector<std::uint8_t> rv;                // per run: state
    const std::size_t expected = rows + (ze - zb) * sz / 32;  // this path's bound, give or take the sampling
    rx.reserve(expected);
    par.reserve(expected);
    rv.reserve(expected);
    const auto end_of = [&](std::uint32_t k, std::uint32_t row_end) -> std::size_t {
      return k + 1 < row_end ? rx[k + 1] : nx;
    };
    // Runs [a0, a1) of this row against runs [b0, b1) of an earlier row: every pair of the same
    // state whose x ranges overlap is united.
    const auto join_overlapping = [&](std::uint32_t a0, std::uint32_t a1, std::uint32_t b0, std::uint32_t b1) {
      std::uint32_t a = a0, b = b0;
      while (a < a1 && b < b1) {
        if (rv[a] == rv[b]) unite(par.data(), a, b);
        const std::size_t ea = end_of(a, a1), eb = end_of(b, b1);
        if (ea <= eb) ++a;
        if (eb <= ea) ++b;
      }
    };
    // Occupied runs [a0, a1) against the occupied runs of an earlier row [b0, b1) that meet
    // [x - 1, e + 1): 26-connectivity across edges and corners.
    const auto join_occupied26 = [&](std::uint32_t a0, std::uint32_t a1, std::uint32_t b0, std::uint32_t b1) {
      std::uint32_t b = b0;
      for (std::uint32_t a = a0; a < a1; ++a) {
        if (rv[a] != kOccupiedState) continue;
        const std::size_t lo = rx[a] > 0 ? rx[a] - 1 : 0, hi = std::min(nx, end_of(a, a1) + 1);
        while (b < b1 && end_of(b, b1) <= lo) ++b;  // runs ending before lo never meet a later run
        for (std::uint32_t c = b; c < b1 && rx[c] < hi; ++c)
          if (rv[c] == kOccupiedState) unite(par.data(), a, c);
      }
    };
    for (std::size_t r = 0; r < rows; ++r) {
      const std::size_t y = r % ny, z = zb + r / ny;
      const std::uint8_t* row = s + nx * (y + ny * z);
      first[r] = static_cast<std::uint32_t>(rx.size());
      for (std::size_t x = 0; x < nx;) {
        const std::size_t e = run_end(row, x, nx);
        par.push_back(static_cast<std::uint32_t>(rx.size()));
        rx.push_back(static_cast<std::uint32_t>(x));
        rv.push_back(row[x]);
        x = e;
      }
      const auto a0 = first[r], a1 = static_cast<std::uint32_t>(rx.size());
      if (y > 0) {  // row y - 1 of this plane
        if (occupied26) join_occupied26(a0, a1, first[r - 1], a0);
        join_overlapping(a0, a1, first[r - 1], a0);
      }
      if (z > zb) {  // the plane below: row y, and for occupied runs rows y - 1 and y + 1 too
        const std::size_t q = r - ny;
        join_overlapping(a0, a1, first[q], first[q + 1]);
        if (occupied26) {
          join_occupied26(a0, a1, first[q], first[q + 1]);
          if (y > 0) join_occupied26(a0, a1, first[q - 1], first[q]);
          if (y + 1 < ny) join_occupied26(a0, a1, first[q + 1], first[q + 2]);
        }
      }
    }
    first[rows] = static_cast<std::uint32_t>(rx.size());
    // Local numbering in place: a run's parent is an earlier run of the slab, already renumbered
    // (the entries are overwritten in index order). Each run start gets its bit; the numbers stay
    // in the table.
    std::uint32_t m = 0;
    for (std::size_t r = 0; r < rows; ++r) {
      const std::size_t i0 = nx * (r % ny + ny * (zb + r / ny));
      for (std::uint32_t k = first[r]; k < first[r + 1]; ++k) {
        const std::size_t rs = i0 + rx[k];
        starts[rs / 8] = static_cast<std::uint8_t>(starts[rs / 8] | (1u << (rs % 8)));
        if (par[k] == k) local_state[sl].push_back(rv[k]);
        par[k] = par[k] == k ? m++ : par[par[k]];
      }
    }
    local_count[sl] = m;
    row_first[sl] = std::move(first);
    run_local[sl].assign(par.begin(), par.end());  // (par holds room for the most runs the path takes)
  };
  for_each_slab(slabs, threads, [&](std::size_t sl) {
    const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
    const std::size_t voxels = (ze - zb) * sz;
    // Every 4th row tells the runs' length well enough (either way gives the same result).
    if (4 * 32 * count_runs(s + zb * sz, (ze - zb) * ny, nx, 4) <= voxels) dense(sl);
    else sparse(sl);
  });

  // 2. Join the slabs: union-find over all local components (global index = base + local id),
  // uniting across each slab's first plane; roots are the earliest components in scan order.
  // Rows of the two planes are walked run by run: one union per pair of touching runs.
  std::vector<std::uint32_t> base(slabs + 1, 0);
  for (std::size_t sl = 0; sl < slabs; ++sl) base[sl + 1] = base[sl] + local_count[sl];
  std::vector<std::uint32_t> parent(base[slabs]);
  for (std::uint32_t k = 0; k < base[slabs]; ++k) parent[k] = k;
  // Local number of the run starting at voxel x of row r of slab sl (map index of the row: i0),
  // the k-th run of its row (k: counted by the caller, or -1 for counting its run starts).
  const auto local_at = [&](std::size_t sl, std::size_t r, std::size_t i0, std::size_t x,
                            std::size_t k = std::size_t(-1)) -> std::uint32_t {
    if (run_local[sl].empty()) return lab[i0 + x];
    if (k == std::size_t(-1)) k = starts_between(starts.data(), i0, i0 + x);
    return run_local[sl][row_first[sl][r] + k];
  };
  const std::size_t last_plane = (kLabelSlab - 1) * ny;  // first row of a full slab's last plane
  // The slabs' first planes at once, on the threads (serially, 1.1 of the scene's 12.5 ms).
  for_each_slab(slabs - 1, threads, [&](std::size_t boundary) {
    const std::size_t sl = boundary + 1, z = sl * kLabelSlab;
    for (std::size_t y = 0; y < ny; ++y) {
      const std::size_t i0 = nx * (y + ny * z), j0 = i0 - sz;  // this row, the row below
      const std::uint8_t *a = s + i0, *b = s + j0;
      // Runs [xa, ea) of this row and [xb, eb) of the row below, stepped along together.
      // (ka, kb: their indices in their rows.)
      std::size_t xa = 0, xb = 0, ea = run_end(a, 0, nx), eb = run_end(b, 0, nx), ka = 0, kb = 0;
      while (true) {
        if (a[xa] == b[xb])
          unite_shared(parent.data(), base[sl] + local_at(sl, y, i0, xa, ka),
                       base[sl - 1] + local_at(sl - 1, last_plane + y, j0, xb, kb));
        const std::size_t e = std::min(ea, eb);
        if (e == nx) break;
        if (ea == e) xa = ea, ea = run_end(a, xa, nx), ++ka;
        if (eb == e) xb = eb, eb = run_end(b, xb, nx), ++kb;
      }
      if (!occupied26) continue;
      // Occupied runs of this row also meet occupied voxels of rows y-1..y+1 below across edges
      // and corners: one voxel wider on both sides.
      for (std::size_t x = 0, ka = 0; x < nx; ++ka) {
        const std::size_t e = run_end(a, x, nx);
        if (a[x] == kOccupiedState) {
          const std::uint32_t ga = base[sl] + local_at(sl, y, i0, x, ka);
          const std::size_t lo = x > 0 ? x - 1 : 0, hi = std::min(nx, e + 1);
          for (std::size_t yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < ny; ++yy) {
            const std::size_t k0 = nx * (yy + ny * (z - 1));
            for_each_run_in(s + k0, kOccupiedState, lo, hi, [&](std::size_t j) {
              unite_shared(parent.data(), ga, base[sl - 1] + local_at(sl - 1, last_plane + yy, k0, j));
            });
          }
        }
        x = e;
      }
    }
  });
  // Final ids in order of first voxel: a component's root precedes it.
  std::vector<std::uint32_t> final_id(base[slabs]);
  std::vector<std::uint8_t> state_of;  // per final id
  for (std::size_t sl = 0; sl < slabs; ++sl) {
    for (std::uint32_t j = 0; j < local_count[sl]; ++j) {
      const std::uint32_t k = base[sl] + j, r = find(parent.data(), k);
      if (r == k) state_of.push_back(local_state[sl][j]);
      final_id[k] = r == k ? static_cast<std::uint32_t>(state_of.size() - 1) : final_id[r];
    }
    local_state[sl] = std::vector<std::uint8_t>();
  }
  const auto count = static_cast<std::uint32_t>(state_of.size());
  parent = std::vector<std::uint32_t>();
  // The states are not read again: a caller that handed them over gets their memory back now,
  // before the statistics (1 byte per voxel less at the peak).
  if (release) release();
  s = nullptr;

  // The segment table, filled slab by slab in slab order below.
  segments.assign(count, Segment());
  // Each segment's integer coordinate sums are kept in the bits of its centroid until the means
  // are taken: a separate array of them was 0.3 byte per voxel at the peak on a noisy map (166,000
  // segments). The centroid's doubles start as 0.0, whose bits are the integer 0.
  auto coordinate_sum = [](Segment& seg, int a) -> std::uint64_t {
    std::uint64_t v;
    std::memcpy(&v, &seg.centroid[a], sizeof v);
    return v;
  };
  for (std::uint32_t k = 0; k < count; ++k) {
    segments[k].id = k;
    segments[k].state = static_cast<State>(state_of[k]);
    segments[k].bbox_min.fill(std::numeric_limits<std::uint32_t>::max());
  }
  auto merge = [&](const detail::ThreadScratch<SlotStats>& slab) {
    for (const SlotStats& t : slab) {
      Segment& seg = segments[t.id];
      seg.voxels += t.voxels;
      seg.mop += t.mop;
      for (int a = 0; a < 3; ++a) {
        seg.bbox_min[a] = std::min(seg.bbox_min[a], t.lo[a]);
        seg.bbox_max[a] = std::max(seg.bbox_max[a], t.hi[a]);
        const std::uint64_t sum = coordinate_sum(seg, a) + t.sum[a];
        std::memcpy(&seg.centroid[a], &sum, sizeof sum);
      }
    }
  };

  // 3. Final labels and per-slab statistics: each slab sums its voxels of every segment in scan
  // order, into one slot per segment present in the slab. Finished slabs are added to the table
  // in slab order as soon as all slabs before them are (whoever finishes one merges what is
  // ready), so only the few slabs waiting for an earlier one keep their slots.
  // (following set_texture_kernel(), so that the tests run both sums)
  [[maybe_unused]] const bool avx512 = cpu_has_avx512() && detail::texture_kernel() >= detail::TextureKernel::avx512;
  std::vector<detail::ThreadScratch<SlotStats>> slots(slabs);
  std::vector<std::uint8_t> finished(slabs, 0);
  std::size_t merged = 0;
  std::mutex merge_mutex;
  for_each_slab(slabs, threads, [&](std::size_t sl) {
    const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
    // Slot of each local component: segments present in this slab, in order of first voxel.
    const std::uint32_t* ids = final_id.data() + base[sl];
    const std::size_t local = local_count[sl];
    std::vector<std::uint32_t> uniq(ids, ids + local);
    std::sort(uniq.begin(), uniq.end());
    uniq.erase(std::unique(uniq.begin(), uniq.end()), uniq.end());
    detail::ThreadScratch<SlotStats>& out = slots[sl];
    out.resize(uniq.size());
    for (std::size_t k = 0; k < uniq.size(); ++k) {
      out[k].id = uniq[k];
      for (int a = 0; a < 3; ++a) {
        out[k].lo[a] = std::numeric_limits<std::uint32_t>::max();
        out[k].hi[a] = 0;
      }
    }
    std::vector<std::uint32_t> slot(local);
    for (std::size_t k = 0; k < local; ++k)
      slot[k] = static_cast<std::uint32_t>(std::lower_bound(uniq.begin(), uniq.end(), ids[k]) - uniq.begin());
    // A dense slab's local numbers, run after run in scan order; a sparse slab's are in the labels.
    const std::uint32_t* numbers = run_local[sl].empty() ? nullptr : run_local[sl].data();
    // The map's values and the label lines 1024 voxels ahead are prefetched, a line at a time as
    // the runs pass (the label lines for writing): the hardware prefetchers stop at every 4 KB
    // page of the map (statistics 9.6 -> 7.9 ms on the scene, one thread).
    constexpr std::size_t kAhead = 1024, kLine = 64 / sizeof(float);
    const std::size_t slab_end = ze * sz;
    std::size_t ahead = zb * sz;
    for (std::size_t z = zb; z < ze; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t i0 = nx * (y + ny * z);
        for (std::size_t x = 0; x < nx;) {
          const std::size_t e = next_start(starts.data(), i0 + x + 1, i0 + nx) - i0;  // a run: one component
          for (const std::size_t to = std::min(slab_end, i0 + e + kAhead); ahead < to; ahead += kLine) {
            __builtin_prefetch(p + ahead);
            __builtin_prefetch(lab + ahead, 1);
          }
          const std::uint32_t l = numbers ? *numbers++ : lab[i0 + x];  // its local number
          SlotStats& t = out[slot[l]];
          std::fill(lab + i0 + x, lab + i0 + e, ids[l]);
#if defined(__x86_64__) && defined(__GNUC__)
          t.mop += avx512 ? run_sum_avx512(p + i0 + x, e - x) : run_sum(p + i0 + x, e - x);  // runs in scan order
#else
          t.mop += run_sum(p + i0 + x, e - x);  // runs in scan order within the slab
#endif
          const std::uint64_t len = e - x;
          t.voxels += len;
          t.sum[0] += (static_cast<std::uint64_t>(x) + e - 1) * len / 2;
          t.sum[1] += y * len;
          t.sum[2] += z * len;
          t.lo[0] = std::min<std::uint32_t>(t.lo[0], static_cast<std::uint32_t>(x));
          t.hi[0] = std::max<std::uint32_t>(t.hi[0], static_cast<std::uint32_t>(e - 1));
          t.lo[1] = std::min<std::uint32_t>(t.lo[1], static_cast<std::uint32_t>(y));
          t.hi[1] = std::max<std::uint32_t>(t.hi[1], static_cast<std::uint32_t>(y));
          t.lo[2] = std::min<std::uint32_t>(t.lo[2], static_cast<std::uint32_t>(z));
          t.hi[2] = std::max<std::uint32_t>(t.hi[2], static_cast<std::uint32_t>(z));
          x = e;
        }
      }
    run_local[sl] = std::vector<std::uint32_t>();
    row_first[sl] = std::vector<std::uint32_t>();
    std::lock_guard<std::mutex> lock(merge_mutex);
    finished[sl] = 1;
    for (; merged < slabs && finished[merged]; ++merged) {
      merge(slots[merged]);
      slots[merged] = detail::ThreadScratch<SlotStats>();
    }
  });

  // 4. Means and centroids.
  for (std::uint32_t k = 0; k < count; ++k) {
    Segment& seg = segments[k];
    const double v = static_cast<double>(seg.voxels);
    seg.mop /= v;
    // Integer coordinate sums are exact; the double sum they replace was exact below 2^53.
    for (int a = 0; a < 3; ++a) seg.centroid[a] = static_cast<double>(coordinate_sum(seg, a)) / v;
  }
}

}  // namespace

void detail::check_labels_fit(std::size_t voxels) {
  if (voxels >= std::numeric_limits<std::uint32_t>::max())
    throw Error(Status::unsupported, "maps of " + std::to_string(voxels) +
                                         " voxels exceed the uint32 labels (at most 2^32 - 2 voxels)");
}

void label_components(const std::vector<std::uint8_t>& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26) {
  std::vector<std::uint8_t> starts;
  label_states(states.data(), nullptr, grid, labels, segments, threads, occupied26, starts);
}

void label_components(std::vector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26) {
  std::vector<std::uint8_t> starts;
  label_states(states.data(), [&] { states = std::vector<std::uint8_t>(); }, grid, labels, segments, threads, occupied26,
               starts);
}

void label_components(UninitVector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26) {
  std::vector<std::uint8_t> starts;
  detail::label_components(std::move(states), grid, labels, segments, threads, occupied26, starts);
}

void detail::label_components(UninitVector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                              std::vector<Segment>& segments, int threads, bool occupied26,
                              std::vector<std::uint8_t>& run_starts) {
  label_states(states.data(), [&] { states = UninitVector<std::uint8_t>(); }, grid, labels, segments, threads,
               occupied26, run_starts);
}

}  // namespace occseg
