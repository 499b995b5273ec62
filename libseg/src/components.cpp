#include "occseg/components.hpp"

#include <algorithm>
#include <limits>
#include <mutex>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "huge_pages.hpp"
#include "segment_internal.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
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

// End of the run of equal labels that starts at x in the label row `l` of length nx. After the
// first pass a row's runs of one state are exactly its runs of one local label (a run is one
// component; neighbours of another state are other components), so the statistics pass finds its
// runs without the states.
inline std::size_t label_run_end(const std::uint32_t* l, std::size_t x, std::size_t nx) {
  const std::uint32_t v = l[x];
  ++x;
#ifdef __SSE2__
  const __m128i vv = _mm_set1_epi32(static_cast<int>(v));
  while (x + 4 <= nx) {
    const auto m = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(
        _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(l + x)), vv))));
    if (m != 0xFu) return x + static_cast<std::size_t>(__builtin_ctz(~m & 0xFu));
    x += 4;
  }
#endif
  while (x < nx && l[x] == v) ++x;
  return x;
}

// Unites a run of state v (label root `rs`) with every stretch of state v in row `other` over
// [lo, hi), one union per stretch (the voxels of a stretch share one run): [lo, hi) is the run's
// own extent for 6-connectivity, one voxel wider on both sides for 26.
inline void unite_range(std::uint32_t* labels, std::uint8_t v, const std::uint8_t* other, std::size_t other_index,
                        std::size_t lo, std::size_t hi, std::uint32_t rs) {
  std::size_t x = lo;
  while (x < hi) {
    x = find_first(other, v, true, x, hi);
    if (x == hi) break;
    unite(labels, rs, labels[other_index + x]);
    x = find_first(other, v, false, x + 1, hi);
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

// label_components() on states `s`; `release`, when given, holds the states and is emptied as
// soon as the components are known (before the statistics pass).
void label_states(const std::uint8_t* s, std::vector<std::uint8_t>* release, const Grid& g,
                  std::vector<std::uint32_t>& labels, std::vector<Segment>& segments, int threads, bool occupied26) {
  const std::size_t n = g.dims.count();
  detail::check_labels_fit(n);
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, nz = g.dims.nz, sz = nx * ny;
  const std::size_t slabs = (nz + kLabelSlab - 1) / kLabelSlab;
  resize_huge(labels, n);
  std::uint32_t* lab = labels.data();
  const float* p = g.p.data();

  // 1. Each slab on its own: runs along x, united with the rows before them in y and z (inside
  // the slab), then numbered 0..m-1 by first voxel; labels hold these local numbers.
  std::vector<std::uint32_t> local_count(slabs, 0);
  std::vector<std::vector<std::uint8_t>> local_state(slabs);  // state of each local component
  for_each_slab(slabs, threads, [&](std::size_t sl) {
    const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
    for (std::size_t z = zb; z < ze; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t i0 = nx * (y + ny * z);
        const std::uint8_t* row = s + i0;
        for (std::size_t x = 0; x < nx;) {
          const std::size_t e = run_end(row, x, nx);
          const auto rs = static_cast<std::uint32_t>(i0 + x);
          std::fill(lab + i0 + x, lab + i0 + e, rs);
          if (occupied26 && row[x] == kOccupiedState) {
            // Neighbours before this run in scan order: row y-1 of this plane and rows y-1..y+1
            // of the plane below, each one voxel wider on both sides.
            const std::size_t lo = x > 0 ? x - 1 : 0, hi = std::min(nx, e + 1);
            if (y > 0) unite_range(lab, kOccupiedState, row - nx, i0 - nx, lo, hi, rs);
            if (z > zb)
              for (std::size_t yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < ny; ++yy) {
                const std::size_t j0 = nx * (yy + ny * (z - 1));
                unite_range(lab, kOccupiedState, s + j0, j0, lo, hi, rs);
              }
          } else {
            if (y > 0) unite_range(lab, row[x], row - nx, i0 - nx, x, e, rs);
            if (z > zb) unite_range(lab, row[x], row - sz, i0 - sz, x, e, rs);
          }
          x = e;
        }
      }
    // Local numbering: a run start's parent is a smaller run start of the slab, already
    // renumbered (the parent array is being overwritten in index order).
    std::uint32_t m = 0;
    for (std::size_t i0 = zb * sz; i0 < ze * sz; i0 += nx)
      for (std::size_t x = 0; x < nx;) {
        const std::size_t e = run_end(s + i0, x, nx);
        const std::size_t rs = i0 + x;
        const std::uint32_t par = lab[rs];
        if (par == rs) local_state[sl].push_back(s[rs]);
        const std::uint32_t id = par == rs ? m++ : lab[par];
        std::fill(lab + rs, lab + i0 + e, id);
        x = e;
      }
    local_count[sl] = m;
  });

  // 2. Join the slabs: union-find over all local components (global index = base + local id),
  // uniting across each slab's first plane; roots are the earliest components in scan order.
  std::vector<std::uint32_t> base(slabs + 1, 0);
  for (std::size_t sl = 0; sl < slabs; ++sl) base[sl + 1] = base[sl] + local_count[sl];
  std::vector<std::uint32_t> parent(base[slabs]);
  for (std::uint32_t k = 0; k < base[slabs]; ++k) parent[k] = k;
  for (std::size_t sl = 1; sl < slabs; ++sl) {
    const std::size_t z = sl * kLabelSlab;
    std::uint32_t last_a = std::numeric_limits<std::uint32_t>::max(), last_b = last_a;
    for (std::size_t i = z * sz; i < (z + 1) * sz; ++i) {
      if (s[i] != s[i - sz]) continue;
      const std::uint32_t a = base[sl] + lab[i], b = base[sl - 1] + lab[i - sz];
      if (a == last_a && b == last_b) continue;
      unite(parent.data(), a, b);
      last_a = a;
      last_b = b;
    }
    if (!occupied26) continue;
    // Occupied voxels of the slab's first plane also meet the 8 diagonal neighbours below. The
    // same pair of components recurs for neighbouring voxels (on a noisy map 9 unions per voxel
    // made this serial loop most of the labelling time): skip a pair just united.
    last_a = last_b = std::numeric_limits<std::uint32_t>::max();
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const std::size_t i = z * sz + y * nx + x;
        if (s[i] != kOccupiedState) continue;
        const std::uint32_t a = base[sl] + lab[i];
        for (std::size_t yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < ny; ++yy)
          for (std::size_t xx = x > 0 ? x - 1 : 0; xx <= x + 1 && xx < nx; ++xx) {
            const std::size_t j = (z - 1) * sz + yy * nx + xx;
            if (s[j] != kOccupiedState) continue;
            const std::uint32_t b = base[sl - 1] + lab[j];
            if (a == last_a && b == last_b) continue;
            unite(parent.data(), a, b);
            last_a = a;
            last_b = b;
          }
      }
  }
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
  if (release) *release = std::vector<std::uint8_t>();
  s = nullptr;

  // The segment table, filled slab by slab in slab order below.
  segments.assign(count, Segment());
  std::vector<std::array<std::uint64_t, 3>> sums(count, {0, 0, 0});
  for (std::uint32_t k = 0; k < count; ++k) {
    segments[k].id = k;
    segments[k].state = static_cast<State>(state_of[k]);
    segments[k].bbox_min.fill(std::numeric_limits<std::uint32_t>::max());
  }
  auto merge = [&](const std::vector<SlotStats>& slab) {
    for (const SlotStats& t : slab) {
      Segment& seg = segments[t.id];
      seg.voxels += t.voxels;
      seg.mop += t.mop;
      for (int a = 0; a < 3; ++a) {
        seg.bbox_min[a] = std::min(seg.bbox_min[a], t.lo[a]);
        seg.bbox_max[a] = std::max(seg.bbox_max[a], t.hi[a]);
        sums[t.id][a] += t.sum[a];
      }
    }
  };

  // 3. Final labels and per-slab statistics: each slab sums its voxels of every segment in scan
  // order, into one slot per segment present in the slab. Finished slabs are added to the table
  // in slab order as soon as all slabs before them are (whoever finishes one merges what is
  // ready), so only the few slabs waiting for an earlier one keep their slots.
  std::vector<std::vector<SlotStats>> slots(slabs);
  std::vector<std::uint8_t> finished(slabs, 0);
  std::size_t merged = 0;
  std::mutex merge_mutex;
  for_each_slab(slabs, threads, [&](std::size_t sl) {
    const std::size_t zb = sl * kLabelSlab, ze = std::min(nz, zb + kLabelSlab);
    // Slot of each local component: segments present in this slab, in order of first voxel.
    std::vector<std::uint32_t> ids(final_id.begin() + base[sl], final_id.begin() + base[sl + 1]);
    std::vector<std::uint32_t> uniq = ids;
    std::sort(uniq.begin(), uniq.end());
    uniq.erase(std::unique(uniq.begin(), uniq.end()), uniq.end());
    std::vector<SlotStats>& out = slots[sl];
    out.resize(uniq.size());
    for (std::size_t k = 0; k < uniq.size(); ++k) {
      out[k].id = uniq[k];
      for (int a = 0; a < 3; ++a) {
        out[k].lo[a] = std::numeric_limits<std::uint32_t>::max();
        out[k].hi[a] = 0;
      }
    }
    std::vector<std::uint32_t> slot(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k)
      slot[k] = static_cast<std::uint32_t>(std::lower_bound(uniq.begin(), uniq.end(), ids[k]) - uniq.begin());
    for (std::size_t z = zb; z < ze; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        const std::size_t i0 = nx * (y + ny * z);
        for (std::size_t x = 0; x < nx;) {
          const std::uint32_t l = lab[i0 + x];
          const std::size_t e = label_run_end(lab + i0, x, nx);  // a run: voxels of one component
          SlotStats& t = out[slot[l]];
          std::fill(lab + i0 + x, lab + i0 + e, ids[l]);
          double acc = t.mop;
          for (std::size_t k = x; k < e; ++k) acc += p[i0 + k];  // scan order within the slab
          t.mop = acc;
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
    std::lock_guard<std::mutex> lock(merge_mutex);
    finished[sl] = 1;
    for (; merged < slabs && finished[merged]; ++merged) {
      merge(slots[merged]);
      slots[merged] = std::vector<SlotStats>();
    }
  });

  // 4. Means and centroids.
  for (std::uint32_t k = 0; k < count; ++k) {
    Segment& seg = segments[k];
    const double v = static_cast<double>(seg.voxels);
    seg.mop /= v;
    // Integer coordinate sums are exact; the double sum they replace was exact below 2^53.
    for (int a = 0; a < 3; ++a) seg.centroid[a] = static_cast<double>(sums[k][a]) / v;
  }
}

}  // namespace

void detail::check_labels_fit(std::size_t voxels) {
  if (voxels >= std::numeric_limits<std::uint32_t>::max())
    throw Error(Status::unsupported, "maps of " + std::to_string(voxels) +
                                         " voxels exceed the uint32 labels (at most 2^32 - 2 voxels)");
}

void label_components(const std::vector<std::uint8_t>& states, const Grid& grid, std::vector<std::uint32_t>& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26) {
  label_states(states.data(), nullptr, grid, labels, segments, threads, occupied26);
}

void label_components(std::vector<std::uint8_t>&& states, const Grid& grid, std::vector<std::uint32_t>& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26) {
  label_states(states.data(), &states, grid, labels, segments, threads, occupied26);
}

}  // namespace occseg
