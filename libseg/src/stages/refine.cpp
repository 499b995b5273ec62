#include "stages/refine.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "occseg/parallel.hpp"
#include "util/huge_pages.hpp"
#include "stages/own_states.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace occseg {

const ScanDirection kSixDirections[6] = {{0, +1}, {0, -1}, {1, +1}, {1, -1}, {2, +1}, {2, -1}};

namespace {

using detail::OwnBits;

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
static_assert(static_cast<int>(State::unknown) == 1, "an unknown bit is the state's value");
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);
constexpr int kMaxLook = 64;  // params.lookahead's upper bound

// The four cases on own states (own[k] == kFree: p below the band, kOccupied: above it).
void classify_own(const std::uint8_t* own, int n, std::uint8_t from, bool* reassign) {
  bool low = false, high = false;
  for (int k = 0; k < n; ++k) {
    low = low || own[k] == kFree;
    high = high || own[k] == kOccupied;
    reassign[k] = false;
  }
  const bool other = (from == kFree) ? low : high;
  const bool own_side = (from == kFree) ? high : low;
  if (!other) return;  // cases i and ii
  for (int k = 0; k < n; ++k)
    reassign[k] = !own_side || ((from == kFree) ? own[k] != kOccupied : own[k] != kFree);  // iii / iv
}

// classify_own() on a window of n voxels entered from state `from` (free or occupied), voxel k at
// pos(k) = (word index, bit) of the bit arrays: the occupied bits first, which alone decide most
// windows (into an object whose voxels are all occupied, or out of one into free space with none:
// no evidence for `from`, nothing moves), the unknown bits only for the others (refinement on the
// noisy map 119-122 -> 106-110 ms, on the scene 6.3 -> 6.0-6.5 ms).
template <class Pos>
void classify_window(const OwnBits& own, int n, std::uint8_t from, bool* reassign, Pos&& pos) {
  std::uint8_t occupied[kMaxLook];
  bool any = false, all = true;
  for (int k = 0; k < n; ++k) {
    const auto [i, b] = pos(k);
    occupied[k] = static_cast<std::uint8_t>((own.occupied[i] >> b) & 1u);
    any = any || occupied[k];
    all = all && occupied[k];
  }
  if (from == kFree ? all : !any) {  // no voxel at the other side of the band from `from`
    std::fill(reassign, reassign + n, false);
    return;
  }
  std::uint8_t win[kMaxLook];
  for (int k = 0; k < n; ++k) {
    const auto [i, b] = pos(k);
    win[k] = occupied[k] ? kOccupied : static_cast<std::uint8_t>((own.unknown[i] >> b) & 1u);  // (kUnknown is 1)
  }
  classify_own(win, n, from, reassign);
}

inline bool is_boundary(std::uint8_t a, std::uint8_t s) {
  return (a == kFree && s == kOccupied) || (a == kOccupied && s == kFree);
}

// ---- vector tests: is there anything to do in these n voxels? ----

// Some free/occupied pair a[x], b[x] (states are 0..2, so only those two differ by xor 2).
__attribute__((target_clones("avx2", "default")))
bool any_boundary(const std::uint8_t* __restrict a, const std::uint8_t* __restrict b, std::size_t n) {
  std::uint8_t any = 0;
  for (std::size_t x = 0; x < n; ++x) any |= static_cast<std::uint8_t>((a[x] ^ b[x]) == (kFree ^ kOccupied));
  return any != 0;
}

// ---- scans along x: one row at a time, rows without any candidate skipped by a vector test ----

// Scan position of the next free/occupied boundary at or after scan position k (k >= 1) of a row
// of len voxels scanned forward (step > 0: pair st[k-1], st[k]) or backward (pair st[j+1], st[j]
// with j = len-1-k); len when there is none. 16 pairs per step where SSE2 exists.
std::size_t next_boundary(const std::uint8_t* st, std::size_t k, std::size_t len, int step) {
  const auto pair = [&](std::size_t q) {
    const std::size_t j = step > 0 ? q : len - 1 - q;
    const std::size_t before = step > 0 ? j - 1 : j + 1;
    return ((st[before] ^ st[j]) & 3) == (kFree ^ kOccupied);
  };
#ifdef __SSE2__
  const __m128i two = _mm_set1_epi8(kFree ^ kOccupied);
  while (k + 16 <= len) {
    // memory span of scan positions [k, k + 16): forward j = k..k+15, backward j = len-k-16..len-1-k
    const std::size_t j0 = step > 0 ? k : len - k - 16;
    const std::size_t b0 = step > 0 ? j0 - 1 : j0 + 1;
    const __m128i x = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(st + j0)),
                                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(st + b0)));
    const auto m = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(x, two)));
    if (m) return step > 0 ? k + static_cast<std::size_t>(__builtin_ctz(m)) : k + 15 - static_cast<std::size_t>(31 - __builtin_clz(m));
    k += 16;
  }
#endif
  while (k < len && !pair(k)) ++k;
  return k;
}

// Row r of the map (states `st`, own states row r of `own`), scanned forward or backward.
void boundary_row(std::uint8_t* st, const OwnBits& own, std::size_t r, std::size_t len, int step, int look) {
  if (len < 2) return;
  if (!any_boundary(st, st + 1, len - 1)) return;  // windows only ever start at a boundary
  const std::ptrdiff_t stride = step;
  std::uint8_t* first = step > 0 ? st : st + len - 1;
  bool re[kMaxLook];
  std::size_t k = 1;
  while ((k = next_boundary(st, k, len, step)) < len) {
    std::uint8_t* c = first + static_cast<std::ptrdiff_t>(k) * stride;
    const std::uint8_t a = c[-stride], s = c[0];
    int n = 0;
    while (n < look && k + n < len && c[n * stride] == s) ++n;
    classify_window(own, n, a, re, [&](int w) {
      const std::size_t q = k + static_cast<std::size_t>(w), x = step > 0 ? q : len - 1 - q;
      return std::pair<std::size_t, unsigned>(r * own.words + x / 64, static_cast<unsigned>(x % 64));
    });
    for (int w = 0; w < n; ++w)
      if (re[w]) c[w * stride] = a;
    k += static_cast<std::size_t>(n);  // resume after the window: no cascade through it
  }
}

// ---- scans along y and z: the lines of one plane advance together, row by row, so every
// access is a contiguous row of nx voxels; each line keeps its own state (its skip count). ----

struct Plane {
  std::size_t rows;    // length of the lines (ny or nz)
  std::ptrdiff_t row;  // distance between successive rows of the plane
};

// Where plane `o` of a scan along `axis` (1 or 2) starts: z = o for y, y = o for z.
inline std::size_t plane_base(const Dims& d, int axis, std::size_t o) { return axis == 1 ? d.nx * d.ny * o : d.nx * o; }
inline Plane plane_shape(const Dims& d, int axis) {
  return axis == 1 ? Plane{d.ny, static_cast<std::ptrdiff_t>(d.nx)} : Plane{d.nz, static_cast<std::ptrdiff_t>(d.nx * d.ny)};
}

// Starts the window of lane x at row k of a plane scan; returns the lane's new skip count. The
// own states of scan row k + w are in row orow + w * ors of `own`. A window that writes occupied
// voxels marks their rows in `occ` (the flag of row k + w is occ_k[w * fs]).
inline std::uint8_t plane_window(std::uint8_t* cur, const OwnBits& own, std::size_t orow, std::ptrdiff_t ors,
                                 std::size_t x, std::ptrdiff_t rs, std::size_t k, std::size_t rows, int look,
                                 std::uint8_t a, std::uint8_t* occ_k, std::ptrdiff_t fs) {
  bool re[kMaxLook];
  const std::uint8_t s = cur[x];
  int n = 1;  // the boundary voxel itself always belongs
  while (n < look && k + n < rows && cur[static_cast<std::ptrdiff_t>(x) + n * rs] == s) ++n;
  // (lane x: the same bit of every row's words)
  const std::size_t i0 = orow * own.words + x / 64;
  const std::ptrdiff_t di = ors * static_cast<std::ptrdiff_t>(own.words);
  const auto b = static_cast<unsigned>(x % 64);
  classify_window(own, n, a, re, [&](int w) {
    return std::pair<std::size_t, unsigned>(static_cast<std::size_t>(static_cast<std::ptrdiff_t>(i0) + w * di), b);
  });
  for (int w = 0; w < n; ++w)
    if (re[w]) {
      cur[static_cast<std::ptrdiff_t>(x) + w * rs] = a;
      if (a == kOccupied) occ_k[w * fs] = 1;
    }
  return static_cast<std::uint8_t>(n - 1);  // resume after the window
}

// Rows the scan of a plane passes over: a free/occupied pair needs an occupied voxel in one of
// its two rows, so a pair of rows without one (flags in `occ`: row r at occ[r * occ_row], a
// superset kept by the windows) is skipped unread; on the benchmark scene 95 % of the rows hold no
// occupied voxel. Running windows still count down there. Row r of the plane has its own states
// in row orow0 + r * occ_row of `own` (the flags are per row of the map too).
void boundary_plane(std::uint8_t* st, const OwnBits& own, std::size_t orow0, std::size_t nx, Plane pl, int step,
                    int look, std::uint8_t* skip, std::uint8_t* occ, std::ptrdiff_t occ_row) {
  std::fill(skip, skip + nx, 0);
  const std::ptrdiff_t rs = pl.row * step;  // signed distance from one row to the next in scan order
  const std::ptrdiff_t fs = occ_row * step;  // the same for the rows' flags (and own states' rows)
  std::uint8_t* first = step > 0 ? st : st + static_cast<std::ptrdiff_t>(pl.rows - 1) * pl.row;
  const std::size_t ofirst = step > 0 ? orow0 : orow0 + (pl.rows - 1) * static_cast<std::size_t>(occ_row);
  std::uint8_t* ffirst = step > 0 ? occ : occ + static_cast<std::ptrdiff_t>(pl.rows - 1) * occ_row;
  std::size_t last_start = 0;  // the last row where a window started (skip counts are < look)
  for (std::size_t k = 1; k < pl.rows; ++k) {
    std::uint8_t* cur = first + static_cast<std::ptrdiff_t>(k) * rs;
    const std::uint8_t* prev = cur - rs;
    const auto ocur = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(ofirst) +
                                               static_cast<std::ptrdiff_t>(k) * fs);  // own states' row
    std::uint8_t* fk = ffirst + static_cast<std::ptrdiff_t>(k) * fs;
    if (!(fk[-fs] | fk[0])) {
      if (k < last_start + static_cast<std::size_t>(look))
        for (std::size_t x = 0; x < nx; ++x) skip[x] = skip[x] ? static_cast<std::uint8_t>(skip[x] - 1) : 0;
      continue;
    }
    // A lane starts a window where it sees a boundary and has none running; running windows count
    // down. Lanes are independent, so a vector test finds the starting lanes of 16 at once.
    std::size_t x = 0;
#ifdef __SSE2__
    const __m128i two = _mm_set1_epi8(kFree ^ kOccupied), zero = _mm_setzero_si128(), one = _mm_set1_epi8(1);
    for (; x + 16 <= nx; x += 16) {
      const __m128i p = _mm_loadu_si128(reinterpret_cast<const __m128i*>(prev + x));
      const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(cur + x));
      const __m128i sk = _mm_loadu_si128(reinterpret_cast<const __m128i*>(skip + x));
      const __m128i start = _mm_and_si128(_mm_cmpeq_epi8(_mm_xor_si128(p, c), two), _mm_cmpeq_epi8(sk, zero));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(skip + x), _mm_subs_epu8(sk, one));
      for (auto m = static_cast<unsigned>(_mm_movemask_epi8(start)); m; m &= m - 1) {
        const std::size_t lane = x + static_cast<std::size_t>(__builtin_ctz(m));
        skip[lane] = plane_window(cur, own, ocur, fs, lane, rs, k, pl.rows, look, prev[lane], fk, fs);
        last_start = k;
      }
    }
#endif
    for (; x < nx; ++x) {
      if (skip[x]) {
        --skip[x];
        continue;
      }
      if (is_boundary(prev[x], cur[x])) {
        skip[x] = plane_window(cur, own, ocur, fs, x, rs, k, pl.rows, look, prev[x], fk, fs);
        last_start = k;
      }
    }
  }
}

// Some occupied voxel among s[0, n).
__attribute__((target_clones("avx2", "default")))
bool any_occupied_row(const std::uint8_t* s, std::size_t n) {
  std::uint8_t any = 0;
  for (std::size_t x = 0; x < n; ++x) any |= static_cast<std::uint8_t>(s[x] == kOccupied);
  return any != 0;
}

// One refinement step: the forward and the backward scan of every line along `axis` for
// free/occupied boundaries, with windows of `look` voxels. (The unknown growth runs on bit masks:
// unknown_growth.cpp.)
struct Sweep {
  int axis;
};

// Runs a list of sweeps, in order, over the whole map, in parallel over independent lines.
//
// The two scans of one line (x) or one plane of lines (y, z) run back to back while its voxels
// are in cache: lines along one axis never share a voxel, so this is the same as the whole
// forward scan followed by the whole backward scan.
//
// Consecutive sweeps along x and y run plane by plane (z fixed), and consecutive sweeps along z
// and x slice by slice (y fixed): the lines of both axes lie inside that plane, so a plane's x
// sweep followed by its y sweep reads and writes exactly what the whole x sweep followed by the
// whole y sweep would. The default call's six sweeps (two passes x y z) read the map four times
// instead of six (docs/performance.md, "Fifth round").
void run_sweeps(std::uint8_t* states, const OwnBits& own, const Dims& d, int threads, int look,
                const std::vector<Sweep>& sweeps, std::uint8_t* occupied_rows = nullptr) {
  std::uint8_t* const st = states;
  // Per row of voxels (row r: y = r % ny, z = r / ny): may hold an occupied voxel. Handed in
  // (`occupied_rows`, found by the unknown growth as it packed the rows), or set from the states
  // with the first group of sweeps; kept by the windows that write occupied voxels; x rows are
  // written only where they held one already.
  std::vector<std::uint8_t> own_flags(occupied_rows ? 0 : d.ny * d.nz, 0);
  std::uint8_t* const occ = occupied_rows ? occupied_rows : own_flags.data();
  bool occ_ready = occupied_rows != nullptr;
  const auto row = [&](std::size_t first, int step) {
    if (occ[first / d.nx]) boundary_row(st + first, own, first / d.nx, d.nx, step, look);
  };
  const auto plane = [&](const Sweep& s, std::size_t o, std::uint8_t* lane, int step) {
    const Plane pl = plane_shape(d, s.axis);
    const std::size_t base = plane_base(d, s.axis, o);
    if (s.axis == 1)  // rows y of plane z = o: rows d.ny * o + y of the map
      boundary_plane(st + base, own, d.ny * o, d.nx, pl, step, look, lane, occ + d.ny * o, 1);
    else  // rows z of slice y = o: rows o + d.ny * z
      boundary_plane(st + base, own, o, d.nx, pl, step, look, lane, occ + o, static_cast<std::ptrdiff_t>(d.ny));
  };
  for (std::size_t g = 0; g < sweeps.size();) {
    // The group's other axis: y (planes of fixed z) or z (slices of fixed y); a lone x sweep
    // runs by planes.
    int other = sweeps[g].axis;
    std::size_t e = g;
    while (e < sweeps.size() && (sweeps[e].axis == 0 || other == 0 || sweeps[e].axis == other)) {
      if (sweeps[e].axis != 0) other = sweeps[e].axis;
      ++e;
    }
    if (other == 0) other = 1;
    const bool by_z = other == 1;  // planes of fixed z, else slices of fixed y
    const bool flag_rows = !occ_ready;
    // the rows of plane z = o (by_z) or of slice y = o: `rows` rows of nx voxels, `stride` apart
    const std::size_t rows = by_z ? d.ny : d.nz, stride = by_z ? d.nx : d.nx * d.ny;
    parallel_for_dynamic(by_z ? d.nz : d.ny, threads, [&](std::size_t o0, std::size_t o1) {
      std::vector<std::uint8_t> lane(d.nx);
      for (std::size_t o = o0; o < o1; ++o) {
        const std::size_t first = by_z ? d.nx * d.ny * o : d.nx * o;
        if (flag_rows)
          for (std::size_t r = 0; r < rows; ++r) {
            const std::size_t i = first + r * stride;
            occ[i / d.nx] = any_occupied_row(st + i, d.nx);
          }
        for (std::size_t k = g; k < e; ++k) {
          const Sweep& s = sweeps[k];
          if (s.axis == 0) {
            for (std::size_t r = 0; r < rows; ++r) {
              row(first + r * stride, +1);
              row(first + r * stride, -1);
            }
          } else {
            plane(s, o, lane.data(), +1);
            plane(s, o, lane.data(), -1);
          }
        }
      }
    });
    occ_ready = occ_ready || flag_rows;
    g = e;
  }
}

std::vector<Sweep> boundary_sweeps(const Params& params) {
  std::vector<Sweep> s;
  for (int pass = 0; pass < params.refine_passes; ++pass)
    for (int axis = 0; axis < 3; ++axis) s.push_back({axis});
  return s;
}

int lookahead_of(const Params& params) { return std::clamp(params.lookahead, 1, kMaxLook); }

}  // namespace

// (A plain function calling the multiversioned one: Clang refuses to make a function declared
// earlier without target_clones multiversioned.)
bool detail::any_occupied(const std::uint8_t* s, std::size_t n) { return any_occupied_row(s, n); }

void detail::float_bounds(double below, double above, float& lo, float& hi) {
  lo = static_cast<float>(below);
  if (static_cast<double>(lo) < below) lo = std::nextafter(lo, 2.0f);
  while (static_cast<double>(std::nextafter(lo, -1.0f)) >= below) lo = std::nextafter(lo, -1.0f);
  hi = static_cast<float>(above);
  if (static_cast<double>(hi) > above) hi = std::nextafter(hi, -1.0f);
  while (static_cast<double>(std::nextafter(hi, 2.0f)) <= above) hi = std::nextafter(hi, 2.0f);
}

std::vector<std::uint8_t> own_states(const Grid& g, const Params& params) {
  std::vector<std::uint8_t> own;
  resize_huge(own, g.p.size());
  float lo, hi;
  detail::float_bounds(params.free_below, params.occupied_above, lo, hi);
  const std::size_t chunk = 1 << 16;
  parallel_for((own.size() + chunk - 1) / chunk, params.threads, [&](std::size_t c0, std::size_t c1) {
    const std::size_t b = c0 * chunk, e = std::min(own.size(), c1 * chunk);
    detail::own_states_of(g.p.data() + b, e - b, lo, hi, own.data() + b);
  });
  return own;
}

void detail::refine_unknown(std::uint8_t* st, const std::uint8_t* own, const Dims& d,
                            const Params& params) {
  grow_unknown(st, own, d, params.threads, nullptr, 0);  // x+, x-, y+, y-, z+, z-
}

void refine_unknown(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                    const Params& params) {
  detail::refine_unknown(st.data(), own.data(), d, params);
}

void detail::refine_boundaries(std::uint8_t* st, const OwnBits& own, const Dims& d, const Params& params) {
  run_sweeps(st, own, d, params.threads, lookahead_of(params), boundary_sweeps(params));
}

void detail::refine(std::uint8_t* st, const OwnBits& own, const Dims& d, const Params& params, std::uint8_t* scratch,
                    std::size_t scratch_bytes, const GrowthRows* growth) {
  // The growth reads every row anyway (or the creation flagged them): rows with an occupied voxel
  // are flagged for the sweeps (the growth never makes or unmakes one), which then need not read
  // the map once more (0.4 ms).
  const bool packed = growth && growth->filled && growth->scratch == scratch;
  std::vector<std::uint8_t> own_flags(growth ? 0 : d.ny * d.nz);  // (growth has room for them)
  std::uint8_t* const occupied_rows = growth ? growth->occupied_rows : own_flags.data();
  grow_unknown(st, nullptr, d, params.threads, scratch, scratch_bytes, own.unknown, occupied_rows, packed,
               packed && !growth->cell_states.empty() ? growth->cell_states.data() : nullptr);
  run_sweeps(st, own, d, params.threads, lookahead_of(params), boundary_sweeps(params), occupied_rows);
}

void refine_boundaries(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                       const Params& params) {
  const detail::OwnBitsStore bits = detail::pack_own_bits(own.data(), d, params.threads);
  detail::refine_boundaries(st.data(), bits.bits, d, params);
}

void refine_unknown(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  refine_unknown(st, own_states(g, params), g.dims, params);
}

void refine_boundaries(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  refine_boundaries(st, own_states(g, params), g.dims, params);
}

void classify_window(const float* p, int n, std::uint8_t from, std::uint8_t into,
                     const Params& params, bool* reassign) {
  bool low = false, high = false;
  for (int k = 0; k < n; ++k) {
    low = low || p[k] < params.free_below;
    high = high || p[k] > params.occupied_above;
    reassign[k] = false;
  }
  // The entered segment's "other side": values that argue for the state we came from.
  const bool other = (from == kFree) ? low : high;
  const bool own = (from == kFree) ? high : low;
  if (!other) return;  // cases i and ii: all at 0.5, or only the entered state's own evidence
  for (int k = 0; k < n; ++k) {
    if (!own) {
      reassign[k] = true;  // case iii: the window argues only for `from`
    } else {               // case iv: mixed; values on `from`'s side or at 0.5 move
      reassign[k] = (from == kFree) ? !(p[k] > params.occupied_above) : !(p[k] < params.free_below);
    }
  }
  (void)into;
}

}  // namespace occseg
