// Stage 5, step 2 (section 3.3): the free/occupied scans with the look-ahead window; refine()
// runs step 1 (refine_unknown.cpp) and then this.
//
// Along each of the six axis directions, at every free->occupied (occupied->free) boundary, the
// voxels just beyond it that belong to the segment entered, up to `lookahead` of them (the
// window), are examined by their own values, and some move to the segment before the boundary
// by the paper's four cases: reassign_window() states them on a window's own states, and
// window_moves() the same on their bits, which every scan calls. The scan resumes after the
// window, so that one boundary never sweeps through a whole segment.
// `refine_passes` passes of the six scans, in the order x+, x-, y+, y-, z+, z-.
//
// How the scans are laid out (they compute what the plain scans of tests/cpp/reference/ do):
//  - own values are read as the own states' bits (detail::OwnBits);
//  - along x a row at a time; along y and z the lines of a plane advance together, row by row,
//    so that every access is a contiguous row of voxels;
//  - a free/occupied pair needs an occupied voxel, so rows without one are skipped;
//  - consecutive sweeps along x and y run plane by plane, along z and x slice by slice.
#include "stages/refine.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "occseg/parallel.hpp"
#include "stages/map_rows.hpp"
#include "stages/own_states.hpp"
#include "util/huge_pages.hpp"

namespace occseg {

const ScanDirection kSixDirections[6] = {{0, +1}, {0, -1}, {1, +1}, {1, -1}, {2, +1}, {2, -1}};

namespace {

using detail::OwnBits;
using detail::word_t;

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
static_assert(static_cast<int>(State::unknown) == 1, "an unknown bit is the state's value");
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);

// ---- The window at one boundary and the four cases ----

constexpr int kMaxLook = 64;  // params.lookahead's upper bound (pipeline/params.cpp)

int lookahead_of(const Params& params) { return std::clamp(params.lookahead, 1, kMaxLook); }

// The window at a boundary: the voxels of the entered segment from the boundary voxel c[0] on,
// `stride` apart, at most `look` of them and at most `room` (the voxels left in the line).
inline int window_length(const std::uint8_t* c, std::ptrdiff_t stride, std::size_t room, int look) {
  int n = 1;  // the boundary voxel itself
  while (n < look && static_cast<std::size_t>(n) < room && c[n * stride] == c[0]) ++n;
  return n;
}

// The four cases for a window entered from state `from` (free or occupied; the segment entered
// has the other one), on its voxels' own states own[0, n): moves[k] says whether voxel k moves to
// `from`. An own value on `from`'s side argues for the state before the boundary, one on the
// entered segment's side for the segment, one at 0.5 for neither:
//   (i)   all at 0.5, or
//   (ii)  only the segment's side (and 0.5): nothing moves;
//   (iii) only `from`'s side (and 0.5): every voxel moves;
//   (iv)  both sides: the voxels on `from`'s side or at 0.5 move.
void reassign_window(const std::uint8_t* own, int n, std::uint8_t from, bool* moves) {
  const std::uint8_t into = from == kFree ? kOccupied : kFree;
  bool for_from = false, for_into = false;
  for (int k = 0; k < n; ++k) {
    for_from = for_from || own[k] == from;
    for_into = for_into || own[k] == into;
  }
  for (int k = 0; k < n; ++k) moves[k] = for_from && (!for_into || own[k] != into);
}

// reassign_window() on a window of the own states' bits, as masks of its voxels: the kernels'
// kernels::window_moves(), which the plane scans' kernel (plane_row) applies too.
using kernels::window_moves;

inline std::uint64_t low_bits(int n) { return n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1; }

// Bits [x, x + n) of a bit row (n <= 64, x + n within the row), bit x first.
inline std::uint64_t bit_field(const word_t* row, std::size_t x, int n) {
  const std::size_t i = x / 64;
  const unsigned b = x % 64;
  std::uint64_t v = row[i] >> b;
  if (b != 0 && b + static_cast<unsigned>(n) > 64) v |= row[i + 1] << (64 - b);
  return v & low_bits(n);
}

// ---- Scans along x: one row at a time ----

// Row r of the map (states `st`, own states row r of `own`), scanned forward or backward.
void scan_row(std::uint8_t* st, const OwnBits& own, std::size_t r, std::size_t len, int step, int look,
              const kernels::RefineKernels& kr) {
  if (len < 2) return;
  if (!kr.any_boundary(st, st + 1, len - 1)) return;  // windows only ever start at a boundary
  const std::ptrdiff_t stride = step;
  std::uint8_t* first = step > 0 ? st : st + len - 1;
  std::size_t q = 1;  // scan position: voxel q forward, len - 1 - q backward
  const word_t* const occ_row = own.occupied + r * own.words;
  const word_t* const unk_row = own.unknown + r * own.words;
  while ((q = kr.next_boundary(st, q, len, step)) < len) {
    std::uint8_t* c = first + static_cast<std::ptrdiff_t>(q) * stride;
    const std::uint8_t from = c[-stride];
    const int n = window_length(c, stride, len - q, look);
    // The window in x order: voxels [xlo, xlo + n) of the row.
    const std::size_t xlo = step > 0 ? q : len - q - static_cast<std::size_t>(n);
    std::uint64_t moves = window_moves(bit_field(occ_row, xlo, n), low_bits(n), from,
                                       [&] { return bit_field(unk_row, xlo, n); });
    for (; moves; moves &= moves - 1) st[xlo + static_cast<std::size_t>(__builtin_ctzll(moves))] = from;
    q += static_cast<std::size_t>(n);  // resume after the window
  }
}

// ---- Scans along y and z: the lines of one plane advance together, row by row; each line (a
// lane x of the rows) keeps its own state, the voxels left in its running window ----

struct Plane {
  std::size_t rows;    // length of the lines (ny or nz)
  std::ptrdiff_t row;  // distance between successive rows of the plane
};

// Where plane `o` of a scan along `axis` (1 or 2) starts: z = o for y, y = o for z.
inline std::size_t plane_base(const Dims& d, int axis, std::size_t o) { return axis == 1 ? d.nx * d.ny * o : d.nx * o; }
inline Plane plane_shape(const Dims& d, int axis) {
  return axis == 1 ? Plane{d.ny, static_cast<std::ptrdiff_t>(d.nx)} : Plane{d.nz, static_cast<std::ptrdiff_t>(d.nx * d.ny)};
}

// One plane's lines, scanned forward or backward, a row of all of them at a time (the kernel's
// plane_row: lanes are independent, a window writes its own lane only). A free/occupied pair
// needs an occupied voxel in one of its two rows, so a pair of rows without one (flags in `occ`:
// row r at occ[r * occ_row], a superset kept by the windows) is skipped unread; running windows
// still count down there. Row r of the plane has its own states in row orow0 + r * occ_row of
// `own` (the flags are per row of the map too). `skip`: nx entries of scratch.
void scan_plane(std::uint8_t* st, const OwnBits& own, std::size_t orow0, std::size_t nx, Plane pl, int step, int look,
                std::uint8_t* skip, std::uint8_t* occ, std::ptrdiff_t occ_row, const kernels::RefineKernels& kr) {
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
    // down. Window row w is scan row k + w, its own states in row ocur + w * fs of `own`.
    const int rows = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(look), pl.rows - k));
    const word_t* occ_rows[kMaxLook];
    const word_t* unk_rows[kMaxLook];
    for (int w = 0; w < rows; ++w) {
      const std::size_t at = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(ocur) + w * fs) * own.words;
      occ_rows[w] = own.occupied + at;
      unk_rows[w] = own.unknown + at;
    }
    const kernels::PlaneRow done = kr.plane_row(prev, cur, rs, rows, skip, nx, occ_rows, unk_rows);
    for (std::uint64_t m = done.occupied_rows; m; m &= m - 1) fk[__builtin_ctzll(m) * fs] = 1;
    if (done.started) last_start = k;
  }
}

// ---- The sweeps: every line along one axis, forward then backward ----

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
// instead of six.
void run_sweeps(std::uint8_t* states, const OwnBits& own, const Dims& d, int threads, int look,
                const std::vector<Sweep>& sweeps, const kernels::RefineKernels& kr,
                std::uint8_t* occupied_rows = nullptr) {
  std::uint8_t* const st = states;
  // Per row of voxels (row r: y = r % ny, z = r / ny): may hold an occupied voxel. Handed in
  // (`occupied_rows`, found by the unknown growth as it packed the rows), or set from the states
  // with the first group of sweeps; kept by the windows that write occupied voxels; x rows are
  // written only where they held one already.
  std::vector<std::uint8_t> own_flags(occupied_rows ? 0 : d.ny * d.nz, 0);
  std::uint8_t* const occ = occupied_rows ? occupied_rows : own_flags.data();
  bool occ_ready = occupied_rows != nullptr;
  const auto row = [&](std::size_t first, int step) {
    if (occ[first / d.nx]) scan_row(st + first, own, first / d.nx, d.nx, step, look, kr);
  };
  const auto plane = [&](const Sweep& s, std::size_t o, std::uint8_t* skip, int step) {
    const Plane pl = plane_shape(d, s.axis);
    const std::size_t base = plane_base(d, s.axis, o);
    if (s.axis == 1)  // rows y of plane z = o: rows d.ny * o + y of the map
      scan_plane(st + base, own, d.ny * o, d.nx, pl, step, look, skip, occ + d.ny * o, 1, kr);
    else  // rows z of slice y = o: rows o + d.ny * z
      scan_plane(st + base, own, o, d.nx, pl, step, look, skip, occ + o, static_cast<std::ptrdiff_t>(d.ny), kr);
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
      std::vector<std::uint8_t> skip(d.nx);
      for (std::size_t o = o0; o < o1; ++o) {
        const std::size_t first = by_z ? d.nx * d.ny * o : d.nx * o;
        if (flag_rows)
          for (std::size_t r = 0; r < rows; ++r) {
            const std::size_t i = first + r * stride;
            occ[i / d.nx] = kr.any_occupied(st + i, d.nx);
          }
        for (std::size_t k = g; k < e; ++k) {
          const Sweep& s = sweeps[k];
          if (s.axis == 0) {
            for (std::size_t r = 0; r < rows; ++r) {
              row(first + r * stride, +1);
              row(first + r * stride, -1);
            }
          } else {
            plane(s, o, skip.data(), +1);
            plane(s, o, skip.data(), -1);
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

}  // namespace

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
  resize_huge(own, g.value_count());
  float lo, hi;
  detail::float_bounds(params.free_below, params.occupied_above, lo, hi);
  if (g.source) {  // row by row, each converted as it is read
    const std::size_t nx = g.dims.nx;
    parallel_for(g.dims.ny * g.dims.nz, params.threads, [&](std::size_t r0, std::size_t r1) {
      detail::MapRows map(g);
      for (std::size_t r = r0; r < r1; ++r) detail::own_states_of(map.run(r * nx, nx), nx, lo, hi, own.data() + r * nx);
    });
    return own;
  }
  const std::size_t chunk = 1 << 16;
  parallel_for((own.size() + chunk - 1) / chunk, params.threads, [&](std::size_t c0, std::size_t c1) {
    const std::size_t b = c0 * chunk, e = std::min(own.size(), c1 * chunk);
    detail::own_states_of(g.values() + b, e - b, lo, hi, own.data() + b);
  });
  return own;
}

void detail::refine(std::uint8_t* st, const OwnBits& own, const Dims& d, const Params& params, std::uint8_t* scratch,
                    std::size_t scratch_bytes, const GrowthRows* growth, const kernels::Table& k) {
  // Step 1. The growth reads every row anyway (or the creation flagged them): rows with an
  // occupied voxel are flagged for the sweeps (the growth never makes or unmakes one), which then
  // need not read the map once more.
  const bool packed = growth && growth->filled && growth->scratch == scratch;
  std::vector<std::uint8_t> own_flags(growth ? 0 : d.ny * d.nz);  // (growth has room for them)
  std::uint8_t* const occupied_rows = growth ? growth->occupied_rows : own_flags.data();
  grow_unknown(st, nullptr, d, params.threads, scratch, scratch_bytes, own.unknown, occupied_rows, packed,
               packed && !growth->cell_states.empty() ? growth->cell_states.data() : nullptr, k);
  // Step 2.
  run_sweeps(st, own, d, params.threads, lookahead_of(params), boundary_sweeps(params), k.refine, occupied_rows);
}

void refine_unknown(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                    const Params& params, const kernels::Table& k) {
  detail::grow_unknown(st.data(), own.data(), d, params.threads, nullptr, 0, nullptr, nullptr, false, nullptr, k);
}

void refine_boundaries(std::vector<std::uint8_t>& st, const std::vector<std::uint8_t>& own, const Dims& d,
                       const Params& params, const kernels::Table& k) {
  const detail::OwnBitsStore bits = detail::pack_own_bits(own.data(), d, params.threads);
  run_sweeps(st.data(), bits.bits, d, params.threads, lookahead_of(params), boundary_sweeps(params), k.refine);
}

void refine_unknown(std::vector<std::uint8_t>& st, const Grid& g, const Params& params, const kernels::Table& k) {
  refine_unknown(st, own_states(g, params), g.dims, params, k);
}

void refine_boundaries(std::vector<std::uint8_t>& st, const Grid& g, const Params& params, const kernels::Table& k) {
  refine_boundaries(st, own_states(g, params), g.dims, params, k);
}

void classify_window(const float* p, int n, std::uint8_t from, std::uint8_t into, const Params& params,
                     bool* reassign) {
  (void)into;  // (the state other than `from`)
  std::vector<std::uint8_t> own(static_cast<std::size_t>(std::max(n, 0)));
  for (int k = 0; k < n; ++k) own[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(params.state_of(p[k]));
  reassign_window(own.data(), n, from, reassign);
}

}  // namespace occseg
