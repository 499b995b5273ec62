// The final labelling (stages/label.hpp): connected components of the voxel states, then the
// segment table.
#include "stages/label.hpp"

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "pipeline/segment_internal.hpp"
#include "util/huge_pages.hpp"
#include "util/thread_scratch.hpp"
#include "stages/map_rows.hpp"

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

// Calls fn(slab) for every slab, through parallel_for_dynamic: slabs differ widely in cost (a
// slab of noise holds many times the runs of a slab of free space), so fixed shares would leave
// threads idle. Each slab's work only writes its own data, so the order changes nothing.
template <typename Fn>
void for_each_slab(std::size_t slabs, int threads, Fn&& fn) {
  parallel_for_dynamic(slabs, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t sl = b; sl < e; ++sl) fn(sl);
  });
}

constexpr std::uint8_t kOccupiedState = static_cast<std::uint8_t>(State::occupied);

// Run starts as bits (voxel i at bit i % 8 of byte i / 8), set row by row (the row_starts
// kernel) as the slabs are labelled: a row's runs are the stretches between its set bits, so the
// labelling walks the runs of a row, and of the rows before it, there (1/8 byte per voxel), and
// the statistics pass finds them there once the states are gone. Slabs are a multiple of 8 voxels
// long, so each slab's thread reads and writes only bytes of its own.
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

// The set bits of `bits` in [i, end), in order, reading no byte at or past byte `last`
// (end <= 8 * last): while the slabs are being labelled, the bytes after a slab's are the next
// slab's. Eight bytes are read at a time, and their bits taken one by one.
class StartsIn {
 public:
  StartsIn(const std::uint8_t* bits, std::size_t i, std::size_t end, std::size_t last)
      : bits_(bits), end_(end), last_(last) {
    fill(i);
  }
  // The next set bit, or `end` when none is left before it.
  std::size_t next() {
    while (!w_) {
      if (stop_ >= end_) return end_;
      fill(stop_);
    }
    const std::size_t j = base_ + static_cast<std::size_t>(__builtin_ctzll(w_));
    w_ &= w_ - 1;
    return j < end_ ? j : end_;
  }

 private:
  // Bits i .. 8 * (i / 8) + 63.
  void fill(std::size_t i) {
    const std::size_t at = i / 8;
    std::uint64_t w = 0;
    if (at + sizeof w <= last_) {
      std::memcpy(&w, bits_ + at, sizeof w);  // little-endian: bit i % 8 of byte i / 8 is bit i % 8
    } else {
      for (std::size_t k = at; k < last_; ++k) w |= static_cast<std::uint64_t>(bits_[k]) << (8 * (k - at));
    }
    w_ = w >> (i % 8);
    base_ = i;
    stop_ = 8 * at + 64;
  }

  const std::uint8_t* bits_;
  const std::size_t end_, last_;
  std::size_t base_ = 0, stop_ = 0;
  std::uint64_t w_ = 0;
};

// The set bits of `bits` in [b, e), from the last (b a multiple of 8; no byte at or past
// ceil(e / 8) is read). next() is called only while some are left.
class StartsBack {
 public:
  StartsBack(const std::uint8_t* bits, std::size_t b, std::size_t e) : bits_(bits), first_(b / 8), at_((e + 7) / 8) {
    load();
    if (e < base_ + 64) w_ &= (std::uint64_t{1} << (e - base_)) - 1;  // (bits of the last byte past e)
  }
  std::size_t next() {
    while (!w_) load();
    const unsigned t = 63u - static_cast<unsigned>(__builtin_clzll(w_));
    w_ &= ~(std::uint64_t{1} << t);
    return base_ + t;
  }

 private:
  // The (up to) 8 bytes before at_.
  void load() {
    const std::size_t n = std::min<std::size_t>(8, at_ - first_);
    at_ -= n;
    std::uint64_t w = 0;
    std::memcpy(&w, bits_ + at_, n);  // little-endian: byte at_ + i is bits 8i..8i+7
    w_ = w;
    base_ = 8 * at_;
  }

  const std::uint8_t* bits_;
  const std::size_t first_;
  std::size_t at_, base_ = 0;
  std::uint64_t w_ = 0;
};

// The run_sum kernel's sum (kernels/label.hpp: lane k % 8 from 0.0, the lanes added pairwise) of
// a run shorter than a lane's turn, inline: most runs of a noisy map are that short, and the
// kernel's call and vector set-up cost more than their few additions.
// (n < 8: voxel k is lane k's only value, added to 0.0; a switch that falls through keeps the
// lanes in registers, where a loop of variable length kept them in memory.)
inline double short_run_sum(const float* v, std::size_t n) {
  double l[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  switch (n) {
    case 7: l[6] = 0.0 + v[6]; [[fallthrough]];
    case 6: l[5] = 0.0 + v[5]; [[fallthrough]];
    case 5: l[4] = 0.0 + v[4]; [[fallthrough]];
    case 4: l[3] = 0.0 + v[3]; [[fallthrough]];
    case 3: l[2] = 0.0 + v[2]; [[fallthrough]];
    case 2: l[1] = 0.0 + v[1]; [[fallthrough]];
    case 1: l[0] = 0.0 + v[0]; [[fallthrough]];
    default: break;
  }
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

// One run in a row's list of runs of its state: [x, e) along x, k its index in scan order.
struct RunRef {
  std::uint32_t x, e, k;
};

// The runs of one plane, row by row, each row's runs of each state apart and in order of x: two
// rows are joined state by state, with no test of states.
class PlaneRuns {
 public:
  // `reserve`: the runs a plane is expected to hold (of any state).
  void reset(std::size_t ny, std::size_t reserve) {
    for (unsigned v = 0; v < 3; ++v) {
      runs_[v].resize(reserve);
      off_[v].assign(ny + 1, 0);
    }
    clear();
  }
  void clear() { row_ = 0; }
  // Room for a row of nx runs, then push() each run, then end_row().
  void begin_row(std::size_t nx) {
    for (unsigned v = 0; v < 3; ++v) {
      const std::size_t n = off_[v][row_];
      if (runs_[v].size() < n + nx) runs_[v].resize(std::max(2 * runs_[v].size(), n + nx));
      at_[v] = runs_[v].data() + n;
    }
  }
  void push(std::uint8_t v, std::uint32_t x, std::uint32_t e, std::uint32_t k) { *at_[v]++ = RunRef{x, e, k}; }
  void end_row() {
    ++row_;
    for (unsigned v = 0; v < 3; ++v) off_[v][row_] = static_cast<std::uint32_t>(at_[v] - runs_[v].data());
  }
  const RunRef* begin(std::size_t y, unsigned v) const { return runs_[v].data() + off_[v][y]; }
  const RunRef* end(std::size_t y, unsigned v) const { return runs_[v].data() + off_[v][y + 1]; }

 private:
  UninitVector<RunRef> runs_[3];       // (their sizes are capacities)
  std::vector<std::uint32_t> off_[3];  // row y's runs of state v: [off_[v][y], off_[v][y + 1])
  RunRef* at_[3] = {nullptr, nullptr, nullptr};
  std::size_t row_ = 0;
};

// Unites every run of [a, a1) with every run of [b, b1) it meets (both rows' runs of one state, in
// order of x): along x they overlap (slack 0) or come within one voxel (slack 1, 26-connectivity).
// Runs of one state in a row are a voxel apart at least, so a run ending first (or both, ending
// together) meets no later run of the other row: one step per run.
template <std::uint32_t slack, typename Unite>
inline void join_rows(const RunRef* a, const RunRef* a1, const RunRef* b, const RunRef* b1, Unite&& unite_ab) {
  while (a < a1 && b < b1) {
    if (a->x < b->e + slack && b->x < a->e + slack) unite_ab(a->k, b->k);
    const bool next_a = a->e <= b->e, next_b = b->e <= a->e;
    a += next_a;
    b += next_b;
  }
}

struct SlotStats {  // one segment's share of one slab
  std::uint32_t id;
  std::uint64_t voxels = 0;
  double mop = 0;
  std::uint32_t lo[3], hi[3];
  std::uint64_t sum[3] = {0, 0, 0};
};

// label_components() on states `s`, in two steps: the connected components (label_slabs(),
// join_slabs(), number_components()), then the segment table with the final labels
// (segment_table()).
//
// The label array is written once, with the final labels: until then only the entry of each
// run's first voxel is used (a run: a maximal stretch of one state along x within a row, which
// lies in one component) of a sparse slab, as its slab-local component number.
// Filling every voxel's entry in the first steps would move the whole array twice more.
class Labelling {
 public:
  Labelling(const std::uint8_t* s, const Grid& g, const kernels::LabelKernels& k, bool occupied26,
            std::uint32_t* lab, std::vector<std::uint8_t>& starts)
      : s_(s), k_(k), nx(g.dims.nx), ny(g.dims.ny), nz(g.dims.nz), sz(nx * ny),
        slabs((nz + kLabelSlab - 1) / kLabelSlab), occupied26_(occupied26), lab_(lab), starts_(starts),
        local_count_(slabs, 0), local_state_(slabs), row_first_(slabs), run_local_(slabs),
        plane_runs_(slabs) {}

  // 1. Each slab on its own: runs along x, united with the runs they touch in the rows before
  // them in y and z (inside the slab), then numbered 0..m-1 by first voxel. The union-find is
  // over the slab's runs by their index in scan order, its parents packed at the start of the
  // slab's own stretch of the label array (4 bytes a run: in L1 or L2, where parents at the run
  // starts, 3.2 MB per slab of 320 x 320, missed L2 at nearly every step). The runs of the plane and of the plane below are listed row by row and state by state
  // (PlaneRuns), so two rows are joined state by state in a merge walk over their runs in x
  // order, reading no state and testing none. The local numbers then go
  // - dense (slabs whose runs are 32 voxels long or more on average, such as the benchmark
  //   scene's): to a table kept for the join and the statistics (4 bytes a run), which write no
  //   label before the statistics;
  // - sparse (shorter runs: noisy maps): to the run starts in the label array, which holds them
  //   anyway: a table of short runs kept until the statistics would raise the peak memory of a
  //   noisy map (0.6 byte per voxel of the default preset's). The lists of two planes of runs 6
  //   voxels long take about half a byte per voxel of a slab, for the one slab each thread has
  //   at a time.
  void label_slabs(int threads) {
    for_each_slab(slabs, threads, [&](std::size_t sl) {
      const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
      const std::size_t voxels = (ze - zb) * sz;
      // Every 4th row tells the runs' length well enough (either way gives the same result).
      const std::size_t sampled = 4 * k_.count_runs(s_ + zb * sz, (ze - zb) * ny, nx, 4);
      const bool dense = 32 * sampled <= voxels;
      const std::size_t rows = (ze - zb) * ny;
      label_slab(sl, dense ? rows + voxels / 32 : rows + sampled + sampled / 8, dense);
    });
  }

  // 2. Joins the slabs: union-find over all local components (global index = base + local id),
  // uniting across each slab's first plane; roots are the earliest components in scan order.
  // Rows of the two planes are walked run by run: one union per pair of touching runs. The
  // slabs' first planes are joined at once, on the threads.
  void join_slabs(int threads) {
    base_.assign(slabs + 1, 0);
    for (std::size_t sl = 0; sl < slabs; ++sl) base_[sl + 1] = base_[sl] + local_count_[sl];
    parent_.resize(base_[slabs]);
    for (std::uint32_t k = 0; k < base_[slabs]; ++k) parent_[k] = k;
    for_each_slab(slabs - 1, threads, [&](std::size_t boundary) { join_plane(boundary + 1); });
  }

  // Final ids in order of first voxel (a component's root precedes it), and each one's state.
  // Then each slab's segments (in order of their first local component) and, in place of each
  // local component's id, its slot among them: the statistics pass sums into the slots without
  // sorting the slab's ids (a noisy map's slabs hold many local components of few segments).
  // The slots are found through a sparse set over the segment ids, in the union-find's storage
  // (a segment has one root at least, so it has room): slot_of[id] is id's slot in the slab being
  // listed when that slot holds id, whatever the stale entry held before.
  void number_components() {
    final_id_.resize(base_[slabs]);
    for (std::size_t sl = 0; sl < slabs; ++sl) {
      for (std::uint32_t j = 0; j < local_count_[sl]; ++j) {
        const std::uint32_t k = base_[sl] + j, r = find(parent_.data(), k);
        if (r == k) state_of_.push_back(local_state_[sl][j]);
        final_id_[k] = r == k ? static_cast<std::uint32_t>(state_of_.size() - 1) : final_id_[r];
      }
      local_state_[sl] = std::vector<std::uint8_t>();
    }
    std::uint32_t* const slot_of = parent_.data();
    segments_in_.resize(slabs);
    for (std::size_t sl = 0; sl < slabs; ++sl) {
      std::vector<std::uint32_t>& in = segments_in_[sl];
      for (std::uint32_t k = base_[sl]; k < base_[sl + 1]; ++k) {
        const std::uint32_t id = final_id_[k];
        std::uint32_t t = slot_of[id];
        if (t >= in.size() || in[t] != id) {
          t = static_cast<std::uint32_t>(in.size());
          slot_of[id] = t;
          in.push_back(id);
        }
        final_id_[k] = t;
      }
    }
    parent_ = std::vector<std::uint32_t>();
  }

  // The states are not read after number_components().
  void forget_states() { s_ = nullptr; }

  // 3. Final labels and the segment table, filled slab by slab: each slab sums its voxels of
  // every segment in scan order, into one slot per segment present in the slab. Finished slabs
  // are added to the table in slab order as soon as all slabs before them are (whoever finishes
  // one merges what is ready), so only the few slabs waiting for an earlier one keep their slots.
  // 4. Means and centroids.
  void segment_table(const Grid& g, std::vector<Segment>& segments, int threads);

 private:
  // Slab sl's runs in a table (`expected`: about how many), united and numbered there; the
  // numbers stay in the table (dense) or go to the run starts in the label array (sparse).
  void label_slab(std::size_t sl, std::size_t expected, bool dense) __attribute__((noinline));
  void join_plane(std::size_t sl);
  void slab_statistics(std::size_t sl, const Grid& g, detail::ThreadScratch<SlotStats>& out);

  // Local number of the run starting at voxel x of row r of slab sl (map index of the row: i0),
  // the k-th run of its row.
  std::uint32_t local_at(std::size_t sl, std::size_t r, std::size_t i0, std::size_t x, std::size_t k) const {
    if (run_local_[sl].empty()) return lab_[i0 + x];
    return run_local_[sl][row_first_[sl][r] + k];
  }

  const std::uint8_t* s_;
  const kernels::LabelKernels& k_;
  const std::size_t nx, ny, nz, sz, slabs;
  const bool occupied26_;
  std::uint32_t* lab_;
  std::vector<std::uint8_t>& starts_;
  // Per slab: the number of its local components and the state of each.
  std::vector<std::uint32_t> local_count_;
  std::vector<std::vector<std::uint8_t>> local_state_;
  // The dense slabs' runs, kept for the join and the statistics: the first run of each row
  // (row_first_) and each run's local number in scan order (run_local_); empty for sparse slabs,
  // whose numbers are at their run starts in the label array. The dense slabs write no label
  // before the statistics: their numbers at the run starts would cost a read and a write of a
  // line of the label array every two runs or so.
  std::vector<std::vector<std::uint32_t>> row_first_, run_local_;
  // Per slab: the runs of its first plane and of its last (for the join's lists).
  std::vector<std::array<std::uint32_t, 2>> plane_runs_;
  std::vector<std::uint32_t> base_;      // per slab: the global index of its local component 0
  std::vector<std::uint32_t> parent_;    // the join's union-find, by global index
  // Per global index: the segment id, then (number_components) its slot in its slab's list.
  std::vector<std::uint32_t> final_id_;
  std::vector<std::vector<std::uint32_t>> segments_in_;  // per slab: the ids of its segments, by slot
  std::vector<std::uint8_t> state_of_;   // per segment id
};

void Labelling::label_slab(std::size_t sl, std::size_t expected, bool dense) {
  const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab), rows = (ze - zb) * ny;
  std::vector<std::uint32_t> first(rows + 1);  // row r's runs: [first[r], first[r + 1]) in scan order
  // Per run, in scan order: its union-find parent, in the slab's own stretch of the label array
  // (a slab holds no more runs than voxels; the statistics overwrite it), and for a dense slab its
  // state (the size a capacity).
  std::uint32_t* const par = lab_ + zb * sz;
  UninitVector<std::uint8_t> rv(dense ? expected : 0);
  // The runs of this plane and of the plane below, by row and state.
  PlaneRuns planes[2];
  for (PlaneRuns& pr : planes) pr.reset(ny, expected / (ze - zb) + nx);
  const bool c26 = occupied26_;
  const std::size_t last = (ze * sz + 7) / 8;  // the slab's run-start bits: bytes before `last`
  std::uint8_t* const bits = starts_.data();
  std::uint32_t k = 0;  // runs so far
  for (std::size_t z = zb; z < ze; ++z) {
    PlaneRuns& cur = planes[(z - zb) % 2];
    const PlaneRuns& below = planes[(z - zb + 1) % 2];
    cur.clear();
    for (std::size_t y = 0; y < ny; ++y) {
      const std::size_t i0 = nx * (y + ny * z);
      const std::uint8_t* row = s_ + i0;
      k_.row_starts(row, nx, bits, i0);
      first[(z - zb) * ny + y] = k;
      if (dense && rv.size() < k + nx) rv.resize(std::max(2 * rv.size(), k + nx));
      cur.begin_row(nx);
      StartsIn runs(bits, i0 + 1, i0 + nx, last);
      for (std::size_t x = 0; x < nx;) {
        const std::size_t e = runs.next() - i0;
        cur.push(row[x], static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(e), k);
        par[k] = k;
        if (dense) rv[k] = row[x];
        ++k;
        x = e;
      }
      cur.end_row();
      std::uint32_t* const pa = par;
      const auto pa_unite = [pa](std::uint32_t a, std::uint32_t b) {
        if (pa[a] != pa[b]) unite(pa, a, b);  // (runs of one set often share their parent already)
      };
      for (unsigned v = 0; v < 3; ++v) {
        const RunRef *a0 = cur.begin(y, v), *a1 = cur.end(y, v);
        if (a0 == a1) continue;
        if (c26 && v == kOccupiedState) {
          // Occupied runs meet occupied runs across edges and corners: one voxel wider.
          if (y > 0) join_rows<1>(a0, a1, cur.begin(y - 1, v), cur.end(y - 1, v), pa_unite);
          if (z > zb)
            for (std::size_t yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < ny; ++yy)
              join_rows<1>(a0, a1, below.begin(yy, v), below.end(yy, v), pa_unite);
        } else {
          if (y > 0) join_rows<0>(a0, a1, cur.begin(y - 1, v), cur.end(y - 1, v), pa_unite);
          if (z > zb) join_rows<0>(a0, a1, below.begin(y, v), below.end(y, v), pa_unite);
        }
      }
    }
  }
  first[rows] = k;
  plane_runs_[sl] = {first[ny], k - first[rows - ny]};
  // Local numbering in place: a run's parent is an earlier run of the slab, already renumbered
  // (the entries are overwritten in index order).
  std::uint32_t m = 0;
  for (std::uint32_t j = 0; j < k; ++j) {
    const std::uint32_t pj = par[j];
    if (pj == j && dense) local_state_[sl].push_back(rv[j]);
    par[j] = pj == j ? m++ : par[pj];
  }
  if (!dense) {
    // The numbers go to the run starts, found in their bits from the last: run j starts at voxel
    // j of the slab or later, so its number overwrites no entry of a run before it, none read
    // yet. Every run of a component has its state.
    local_state_[sl].resize(m);
    StartsBack starts(bits, zb * sz, ze * sz);
    for (std::uint32_t j = k; j-- > 0;) {
      const std::size_t rs = starts.next();
      const std::uint32_t id = par[j];
      local_state_[sl][id] = s_[rs];
      lab_[rs] = id;
    }
  }
  local_count_[sl] = m;
  if (dense) {
    row_first_[sl] = std::move(first);
    run_local_[sl].assign(par, par + k);
  }
}

// Unites the components of slab sl's first plane with those they touch in the plane below: both
// planes listed by row and state, with the global index of each run's component, and joined row
// by row as in a slab.
void Labelling::join_plane(std::size_t sl) {
  const std::size_t z = sl * kLabelSlab;
  const std::size_t last_plane = (kLabelSlab - 1) * ny;  // first row of a full slab's last plane
  const std::uint8_t* const bits = starts_.data();        // every slab's, all set by now
  std::uint32_t* const parent = parent_.data();
  PlaneRuns above, below;
  const auto list = [&](PlaneRuns& pr, std::size_t slab, std::size_t zz, std::size_t row0, std::size_t runs) {
    pr.reset(ny, runs + nx);
    const std::uint32_t base = base_[slab];
    for (std::size_t y = 0; y < ny; ++y) {
      const std::size_t i0 = nx * (y + ny * zz);
      const std::uint8_t* row = s_ + i0;
      pr.begin_row(nx);
      StartsIn runs(bits, i0 + 1, i0 + nx, starts_.size());
      for (std::size_t x = 0, k = 0; x < nx; ++k) {
        const std::size_t e = runs.next() - i0;
        pr.push(row[x], static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(e),
                base + local_at(slab, row0 + y, i0, x, k));
        x = e;
      }
      pr.end_row();
    }
  };
  list(above, sl, z, 0, plane_runs_[sl][0]);
  list(below, sl - 1, z - 1, last_plane, plane_runs_[sl - 1][1]);
  const auto unite_at = [parent](std::uint32_t a, std::uint32_t b) { unite_shared(parent, a, b); };
  for (std::size_t y = 0; y < ny; ++y)
    for (unsigned v = 0; v < 3; ++v) {
      const RunRef *a0 = above.begin(y, v), *a1 = above.end(y, v);
      if (a0 == a1) continue;
      if (occupied26_ && v == kOccupiedState) {
        for (std::size_t yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < ny; ++yy)
          join_rows<1>(a0, a1, below.begin(yy, v), below.end(yy, v), unite_at);
      } else {
        join_rows<0>(a0, a1, below.begin(y, v), below.end(y, v), unite_at);
      }
    }
}

void Labelling::segment_table(const Grid& g, std::vector<Segment>& segments, int threads) {
  const auto count = static_cast<std::uint32_t>(state_of_.size());
  segments.assign(count, Segment());
  // Each segment's integer coordinate sums are kept in the bits of its centroid until the means
  // are taken: a separate array of them (24 bytes per segment) would add 0.3 byte per voxel at
  // the peak of a noisy map, which has a segment per 80 voxels or so. The centroid's doubles
  // start as 0.0, whose bits are the integer 0.
  auto coordinate_sum = [](Segment& seg, int a) -> std::uint64_t {
    std::uint64_t v;
    std::memcpy(&v, &seg.centroid[a], sizeof v);
    return v;
  };
  for (std::uint32_t k = 0; k < count; ++k) {
    segments[k].id = k;
    segments[k].state = static_cast<State>(state_of_[k]);
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
  std::vector<detail::ThreadScratch<SlotStats>> slots(slabs);
  std::vector<std::uint8_t> finished(slabs, 0);
  std::size_t merged = 0;
  std::mutex merge_mutex;
  for_each_slab(slabs, threads, [&](std::size_t sl) {
    slab_statistics(sl, g, slots[sl]);
    run_local_[sl] = std::vector<std::uint32_t>();
    row_first_[sl] = std::vector<std::uint32_t>();
    segments_in_[sl] = std::vector<std::uint32_t>();
    std::lock_guard<std::mutex> lock(merge_mutex);
    finished[sl] = 1;
    for (; merged < slabs && finished[merged]; ++merged) {
      merge(slots[merged]);
      slots[merged] = detail::ThreadScratch<SlotStats>();
    }
  });

  for (std::uint32_t k = 0; k < count; ++k) {
    Segment& seg = segments[k];
    const double v = static_cast<double>(seg.voxels);
    seg.mop /= v;
    // Integer coordinate sums are exact (a sum in double would be exact only below 2^53).
    for (int a = 0; a < 3; ++a) seg.centroid[a] = static_cast<double>(coordinate_sum(seg, a)) / v;
  }
}

// Slab sl's final labels, and its share of every segment present in it (in `out`, by slot),
// summed run by run in scan order.
void Labelling::slab_statistics(std::size_t sl, const Grid& g, detail::ThreadScratch<SlotStats>& out) {
  const float* const p = g.values();  // null for a grid read through a source: `map` converts each row
  detail::MapRows map(g);
  const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
  std::uint32_t* const lab = lab_;
  // Slot of each local component (number_components()): the segments present in this slab, in
  // order of their first local component. (Each segment's sums go to one slot per slab, in scan
  // order, and are merged slab by slab: the order of the slots changes no sum.)
  const std::uint32_t* const slot = final_id_.data() + base_[sl];
  const std::vector<std::uint32_t>& in = segments_in_[sl];
  out.resize(in.size());
  for (std::size_t k = 0; k < in.size(); ++k) {
    out[k].id = in[k];
    for (int a = 0; a < 3; ++a) {
      out[k].lo[a] = std::numeric_limits<std::uint32_t>::max();
      out[k].hi[a] = 0;
    }
  }
  // A dense slab's local numbers, run after run in scan order; a sparse slab's are in the labels.
  const std::uint32_t* numbers = run_local_[sl].empty() ? nullptr : run_local_[sl].data();
  // The map's values and the label lines 1024 voxels ahead are prefetched, a line at a time as
  // the runs pass (the label lines for writing): the hardware prefetchers stop at every 4 KB
  // page of the map.
  constexpr std::size_t kAhead = 1024, kLine = 64 / sizeof(float);
  const std::size_t slab_end = ze * sz;
  std::size_t ahead = zb * sz;
  for (std::size_t z = zb; z < ze; ++z)
    for (std::size_t y = 0; y < ny; ++y) {
      const std::size_t i0 = nx * (y + ny * z);
      const float* const prow = map.run(i0, nx);
      for (std::size_t x = 0; x < nx;) {
        const std::size_t e = next_start(starts_.data(), i0 + x + 1, i0 + nx) - i0;  // a run: one component
        for (const std::size_t to = std::min(slab_end, i0 + e + kAhead); ahead < to; ahead += kLine) {
          if (p) __builtin_prefetch(p + ahead);
          __builtin_prefetch(lab + ahead, 1);
        }
        const std::uint32_t l = numbers ? *numbers++ : lab[i0 + x];  // its local number
        SlotStats& t = out[slot[l]];
        std::fill(lab + i0 + x, lab + i0 + e, t.id);
        const std::uint64_t len = e - x;
        // (runs in scan order within the slab)
        t.mop += len < 8 ? short_run_sum(prow + x, len) : k_.run_sum(prow + x, len);
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
}

// label_components() on states `s`; `release`, when given, frees the states as soon as the
// components are known (before the statistics pass).
void label_states(const std::uint8_t* s, const std::function<void()>& release, const Grid& g,
                  LabelArray& labels, std::vector<Segment>& segments, int threads, bool occupied26,
                  std::vector<std::uint8_t>& starts, const kernels::Table& k) {
  const std::size_t n = g.dims.count();
  detail::check_labels_fit(n);
  resize_huge(labels, n);
  starts.assign(n / 8 + 9, 0);  // run starts, for the statistics pass (storage kept if large enough)
  Labelling labelling(s, g, k.label, occupied26, labels.data(), starts);
  // The connected components of the states.
  labelling.label_slabs(threads);
  labelling.join_slabs(threads);
  labelling.number_components();
  // The states are not read again: a caller that handed them over gets their memory back now,
  // before the statistics (1 byte per voxel less at the peak).
  labelling.forget_states();
  if (release) release();
  // Then the segment table.
  labelling.segment_table(g, segments, threads);
}

}  // namespace

void detail::check_labels_fit(std::size_t voxels) {
  if (voxels >= std::numeric_limits<std::uint32_t>::max())
    throw Error(Status::unsupported, "maps of " + std::to_string(voxels) +
                                         " voxels exceed the uint32 labels (at most 2^32 - 2 voxels)");
}

void label_components(const std::vector<std::uint8_t>& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26, const kernels::Table& k) {
  std::vector<std::uint8_t> starts;
  label_states(states.data(), nullptr, grid, labels, segments, threads, occupied26, starts, k);
}

void label_components(std::vector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26, const kernels::Table& k) {
  std::vector<std::uint8_t> starts;
  label_states(states.data(), [&] { states = std::vector<std::uint8_t>(); }, grid, labels, segments, threads, occupied26,
               starts, k);
}

void label_components(UninitVector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26, const kernels::Table& k) {
  std::vector<std::uint8_t> starts;
  detail::label_components(std::move(states), grid, labels, segments, threads, occupied26, starts, k);
}

void detail::label_components(UninitVector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                              std::vector<Segment>& segments, int threads, bool occupied26,
                              std::vector<std::uint8_t>& run_starts, const kernels::Table& k) {
  // (The states are freed before the statistics, for the statistics' table to reuse.)
  label_states(states.data(), [&] { states = UninitVector<std::uint8_t>(); }, grid, labels, segments, threads,
               occupied26, run_starts, k);
}

}  // namespace occseg
