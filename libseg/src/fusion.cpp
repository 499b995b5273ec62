#include "occseg/fusion.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <emmintrin.h>
#include <immintrin.h>
#include <limits>
#include <mutex>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "cpu_features.hpp"
#include "huge_pages.hpp"

namespace occseg {

namespace {
double logit(double p) { return std::log(p / (1 - p)); }
std::atomic<bool> g_vector_walk{true};
// The AVX2 walk where the processor has AVX2 (checked at run time: the library is built for
// generic x86-64) and no test asked for the SSE2 one.
[[maybe_unused]] bool use_avx2() { return cpu_has_avx2() && g_vector_walk.load(std::memory_order_relaxed); }
}  // namespace

namespace detail {
void set_vector_walk(bool enabled) { g_vector_walk.store(enabled, std::memory_order_relaxed); }
}  // namespace detail

void SensorModel::validate() const {
  auto in01 = [](const char* name, double v) {
    if (!(v > 0 && v < 1))
      throw Error(Status::invalid_argument, std::string("sensor model ") + name + " = " +
                                                std::to_string(v) + " is not in (0, 1)");
  };
  in01("p_hit", p_hit);
  in01("p_miss", p_miss);
  in01("clamp_min", clamp_min);
  in01("clamp_max", clamp_max);
  if (p_hit <= 0.5) throw Error(Status::invalid_argument, "sensor model p_hit must be above 0.5");
  if (p_miss >= 0.5) throw Error(Status::invalid_argument, "sensor model p_miss must be below 0.5");
  if (clamp_min >= 0.5 || clamp_max <= 0.5)
    throw Error(Status::invalid_argument, "sensor model clamping must bracket 0.5");
  if (std::isnan(max_range)) throw Error(Status::invalid_argument, "sensor model max_range is NaN");
}

OccupancyFusion::OccupancyFusion(const GridFrame& frame, const SensorModel& model)
    : frame_(frame), model_(model) {
  check_dims(frame.dims);
  model.validate();
  if (!(frame.voxel_size > 0) || !std::isfinite(frame.voxel_size))
    throw Error(Status::bad_value, "voxel size " + std::to_string(frame.voxel_size) + " is not positive");
  for (double o : frame.origin)
    if (!std::isfinite(o)) throw Error(Status::bad_value, "grid origin is not finite");
  l_hit_ = static_cast<float>(logit(model.p_hit));
  l_miss_ = static_cast<float>(logit(model.p_miss));
  l_min_ = static_cast<float>(logit(model.clamp_min));
  l_max_ = static_cast<float>(logit(model.clamp_max));
  resize_huge(log_odds_, frame.dims.count());  // zero-filled, on 2 MB pages where possible
  resize_huge(marks_, frame.dims.count());
}

namespace {

// Voxels a scan may have marked: per axis, the range between the first and the last cell of
// every walk (walks are monotone along each axis). The apply pass only visits this box.
struct TouchBox {
  long lo[3] = {std::numeric_limits<long>::max(), std::numeric_limits<long>::max(),
                std::numeric_limits<long>::max()};
  long hi[3] = {-1, -1, -1};
  void add(const long* c) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], c[k]);
      hi[k] = std::max(hi[k], c[k]);
    }
  }
  void merge(const TouchBox& o) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], o.lo[k]);
      hi[k] = std::max(hi[k], o.hi[k]);
    }
  }
  bool empty() const { return hi[0] < lo[0]; }
};

// Marks one voxel as crossed. While rays are walked only this value is ever written (hits are
// collected in lists and written after every walk is done, see insert_scan), so concurrent
// walks need no locked read-modify-write: a relaxed load and, on an unmarked voxel, a relaxed
// store. Reading first keeps the cache line shared between threads where many rays cross (near
// the sensor) instead of bouncing it with stores.
inline void mark_crossed(std::uint8_t* m) {
  if (__atomic_load_n(m, __ATOMIC_RELAXED) == 0) __atomic_store_n(m, std::uint8_t(1), __ATOMIC_RELAXED);
}

// One Amanatides & Woo voxel traversal in progress. Each step depends on the previous one (compare
// tmax, add tdelta: about 9 cycles of latency for a few instructions), so rays are walked several
// at a time, one step each in turn, and the processor overlaps their chains.
struct Walk {
  __m128d tx, ty, tz, dx, dy, dz;  // tmax and tdelta per axis, in the low lane
  std::uint64_t i, end, sx, sy, sz;  // voxel index, end voxel index, index strides of one step
  long rx, ry, rz, budget;          // steps left along each axis inside the grid; steps left
  long c0[3], room[3], step[3];     // start voxel, initial room, step signs (for the touched box)
  bool hit;                         // the end voxel holds a return (else it is only crossed)
  bool at_end;                      // the walk stopped on its end voxel (set when it is over)
};

// Sets up the traversal of the segment a -> b (grid units: (world - origin) / voxel_size),
// clipped to the grid box; false when the segment misses the box. The floating-point arithmetic
// (clipping, tmax, tdelta, and in step() the axis choice and tmax updates) is exactly that of
// the first implementation, so the same voxels are visited; what changed is the bookkeeping.
bool start_walk(const double* a, const double* b, bool hit, const Dims& dims, Walk& w, TouchBox& box) {
  const double n[3] = {double(dims.nx), double(dims.ny), double(dims.nz)};
  double d[3];
  for (int k = 0; k < 3; ++k) d[k] = b[k] - a[k];
  // Clip the parameter range [t0, t1] of a + t d to the box [0, n] (slab method).
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (a[k] < 0 || a[k] >= n[k]) return false;
      continue;
    }
    double ta = (0 - a[k]) / d[k], tb = (n[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return false;
  const bool end_inside = hit && t1 >= 1.0;
  const std::uint64_t nx = dims.nx, nxy = nx * dims.ny;
  long c[3], last[3];
  double tmax[3], tdelta[3];
  for (int k = 0; k < 3; ++k) {
    const double p = a[k] + t0 * d[k];
    c[k] = std::clamp(static_cast<long>(std::floor(p)), 0L, static_cast<long>(n[k]) - 1);
    const double q = a[k] + t1 * d[k];
    last[k] = std::clamp(static_cast<long>(std::floor(q)), 0L, static_cast<long>(n[k]) - 1);
    if (d[k] > 0) {
      w.step[k] = 1;
      tmax[k] = (c[k] + 1 - a[k]) / d[k];
      tdelta[k] = 1 / d[k];
    } else if (d[k] < 0) {
      w.step[k] = -1;
      tmax[k] = (c[k] - a[k]) / d[k];
      tdelta[k] = -1 / d[k];
    } else {
      w.step[k] = 0;
      tmax[k] = tdelta[k] = std::numeric_limits<double>::infinity();
    }
    w.c0[k] = c[k];
    // Steps left along the axis before the walk would leave the grid (the first implementation
    // stopped there); an axis with d = 0 is never taken (its tmax is +inf).
    w.room[k] = w.step[k] > 0 ? static_cast<long>(n[k]) - 1 - c[k]
                              : (w.step[k] < 0 ? c[k] : std::numeric_limits<long>::max());
  }
  box.add(c);
  // Bounded walk: at most the number of voxel faces crossed plus one.
  w.budget = std::labs(last[0] - c[0]) + std::labs(last[1] - c[1]) + std::labs(last[2] - c[2]) + 1;
  w.i = static_cast<std::uint64_t>(c[0]) + nx * static_cast<std::uint64_t>(c[1]) + nxy * static_cast<std::uint64_t>(c[2]);
  w.end = static_cast<std::uint64_t>(last[0]) + nx * static_cast<std::uint64_t>(last[1]) +
          nxy * static_cast<std::uint64_t>(last[2]);
  // Unsigned wrap-around makes a step of -1 subtract the stride.
  w.sx = static_cast<std::uint64_t>(w.step[0]);
  w.sy = static_cast<std::uint64_t>(w.step[1]) * nx;
  w.sz = static_cast<std::uint64_t>(w.step[2]) * nxy;
  w.rx = w.room[0];
  w.ry = w.room[1];
  w.rz = w.room[2];
  w.tx = _mm_set_sd(tmax[0]);
  w.ty = _mm_set_sd(tmax[1]);
  w.tz = _mm_set_sd(tmax[2]);
  w.dx = _mm_set_sd(tdelta[0]);
  w.dy = _mm_set_sd(tdelta[1]);
  w.dz = _mm_set_sd(tdelta[2]);
  w.hit = end_inside;
  w.at_end = false;
  return true;
}

// Marks the current voxel crossed and moves one voxel on; false when the walk is over (at_end
// tells whether it stopped on its end voxel). The axis is chosen with compare masks, not
// branches (the choice is a coin flip on oblique rays), and each tmax gets + tdelta or + 0.0,
// which leaves it unchanged.
inline bool step(Walk& w, std::uint8_t* marks) {
  mark_crossed(marks + w.i);
  if (w.i == w.end) {
    w.at_end = true;
    return false;
  }
  // Same choice as tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2).
  const __m128d xy = _mm_cmplt_sd(w.tx, w.ty), xz = _mm_cmplt_sd(w.tx, w.tz), yz = _mm_cmplt_sd(w.ty, w.tz);
  const __m128d mx = _mm_and_pd(xy, xz), my = _mm_andnot_pd(xy, yz);
  const __m128d mz = _mm_andnot_pd(_mm_or_pd(mx, my), _mm_castsi128_pd(_mm_set1_epi32(-1)));
  w.tx = _mm_add_sd(w.tx, _mm_and_pd(mx, w.dx));
  w.ty = _mm_add_sd(w.ty, _mm_and_pd(my, w.dy));
  w.tz = _mm_add_sd(w.tz, _mm_and_pd(mz, w.dz));
  const std::int64_t kx = _mm_cvtsi128_si64(_mm_castpd_si128(mx));  // 0 or -1
  const std::int64_t ky = _mm_cvtsi128_si64(_mm_castpd_si128(my));
  const std::int64_t kz = _mm_cvtsi128_si64(_mm_castpd_si128(mz));
  w.i += (w.sx & static_cast<std::uint64_t>(kx)) | (w.sy & static_cast<std::uint64_t>(ky)) |
         (w.sz & static_cast<std::uint64_t>(kz));
  w.rx += kx;
  w.ry += ky;
  w.rz += kz;
  if ((w.rx | w.ry | w.rz) < 0) return false;
  return --w.budget > 0;
}

// Adds the voxels a finished walk covered to the box: walks are monotone along each axis, and
// went no further than the steps they took (a step out of the grid was counted, not taken). A
// walk that reached its end voxel with a return lists it in `hits`.
void finish_walk(const Walk& w, const Dims& dims, TouchBox& box, std::vector<std::uint64_t>& hits) {
  const long moved[3] = {w.room[0] - w.rx, w.room[1] - w.ry, w.room[2] - w.rz};
  const long n[3] = {static_cast<long>(dims.nx), static_cast<long>(dims.ny), static_cast<long>(dims.nz)};
  long fin[3];
  for (int k = 0; k < 3; ++k) fin[k] = std::clamp(w.c0[k] + w.step[k] * moved[k], 0L, n[k] - 1);
  box.add(fin);
  if (w.at_end && w.hit) hits.push_back(w.end);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define OCCSEG_FUSION_AVX2 1
// Four walks in the four lanes of AVX2 registers, one step of each per iteration: the same IEEE
// operations as step() (LT_OS compares, masked adds of tdelta), so the same voxels, at about a
// quarter of the instructions per voxel step (two groups of four lanes per iteration were slower:
// register spills). Lanes go to memory only when one of them ends (about once per hundred steps).
// All lanes start live; `refill(k)` starts the next ray in w[k] and returns false when there is
// none: then live[k] turns false and the function returns, leaving the walks still going in `w`
// for step() to finish.
constexpr int kVectorLanes = 4;

struct alignas(32) Lanes {
  double tx[kVectorLanes], ty[kVectorLanes], tz[kVectorLanes], dx[kVectorLanes], dy[kVectorLanes], dz[kVectorLanes];
  std::int64_t i[kVectorLanes], end[kVectorLanes], sx[kVectorLanes], sy[kVectorLanes], sz[kVectorLanes];
  std::int64_t rx[kVectorLanes], ry[kVectorLanes], rz[kVectorLanes], budget[kVectorLanes];
  void put(int k, const Walk& w) {
    // Memory forms only: Valgrind (3.19) cannot decode the register form of VEX movq that
    // _mm_set_sd / _mm_cvtsd_f64 may compile to, and users run their programs under it.
    _mm_store_sd(tx + k, w.tx), _mm_store_sd(ty + k, w.ty), _mm_store_sd(tz + k, w.tz);
    _mm_store_sd(dx + k, w.dx), _mm_store_sd(dy + k, w.dy), _mm_store_sd(dz + k, w.dz);
    i[k] = std::int64_t(w.i), end[k] = std::int64_t(w.end);
    sx[k] = std::int64_t(w.sx), sy[k] = std::int64_t(w.sy), sz[k] = std::int64_t(w.sz);
    rx[k] = w.rx, ry[k] = w.ry, rz[k] = w.rz, budget[k] = w.budget;
  }
  void get(int k, Walk& w) const {
    w.tx = _mm_load_sd(tx + k), w.ty = _mm_load_sd(ty + k), w.tz = _mm_load_sd(tz + k);
    w.dx = _mm_load_sd(dx + k), w.dy = _mm_load_sd(dy + k), w.dz = _mm_load_sd(dz + k);
    w.i = std::uint64_t(i[k]), w.end = std::uint64_t(end[k]);
    w.sx = std::uint64_t(sx[k]), w.sy = std::uint64_t(sy[k]), w.sz = std::uint64_t(sz[k]);
    w.rx = rx[k], w.ry = ry[k], w.rz = rz[k], w.budget = budget[k];
  }
};

// Four 64-bit lanes of a Lanes field (lambdas would not inherit the target attribute).
__attribute__((target("avx2"))) inline __m256i load(const std::int64_t* f) {
  return _mm256_load_si256(reinterpret_cast<const __m256i*>(f));
}
__attribute__((target("avx2"))) inline void store(std::int64_t* f, __m256i v) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(f), v);
}

template <typename Refill>
__attribute__((target("avx2"))) void walk_vector_avx2(Walk (&w)[kVectorLanes], bool (&live)[kVectorLanes],
                                                      std::uint8_t* marks, const Dims& dims, TouchBox& box,
                                                      std::vector<std::uint64_t>& hits, Refill&& refill) {
  Lanes L;
  for (int k = 0; k < kVectorLanes; ++k) L.put(k, w[k]);
  const __m256i ones = _mm256_set1_epi64x(-1), zero = _mm256_setzero_si256();
  for (;;) {
    __m256d tx = _mm256_load_pd(L.tx), ty = _mm256_load_pd(L.ty), tz = _mm256_load_pd(L.tz);
    const __m256d dx = _mm256_load_pd(L.dx), dy = _mm256_load_pd(L.dy), dz = _mm256_load_pd(L.dz);
    __m256i i = load(L.i), rx = load(L.rx), ry = load(L.ry), rz = load(L.rz), budget = load(L.budget);
    const __m256i end = load(L.end), sx = load(L.sx), sy = load(L.sy), sz = load(L.sz);
    int done = 0, eqm = 0;
    while (!done) {
      alignas(32) std::uint64_t at[4];
      _mm256_store_si256(reinterpret_cast<__m256i*>(at), i);
      const __m256i eq = _mm256_cmpeq_epi64(i, end);
      eqm = _mm256_movemask_pd(_mm256_castsi256_pd(eq));  // lanes on their end voxel: over
      for (int k = 0; k < 4; ++k) mark_crossed(marks + at[k]);
      const __m256d xy = _mm256_cmp_pd(tx, ty, _CMP_LT_OS), xz = _mm256_cmp_pd(tx, tz, _CMP_LT_OS);
      const __m256d yz = _mm256_cmp_pd(ty, tz, _CMP_LT_OS);
      const __m256d mx = _mm256_and_pd(xy, xz), my = _mm256_andnot_pd(xy, yz);
      const __m256d mz = _mm256_andnot_pd(_mm256_or_pd(mx, my), _mm256_castsi256_pd(ones));
      // A lane at its end voxel is over (step() returns before moving); its tmax and index are
      // not used again, only its room counters must not move.
      tx = _mm256_add_pd(tx, _mm256_and_pd(mx, dx));
      ty = _mm256_add_pd(ty, _mm256_and_pd(my, dy));
      tz = _mm256_add_pd(tz, _mm256_and_pd(mz, dz));
      const __m256i kx = _mm256_andnot_si256(eq, _mm256_castpd_si256(mx));
      const __m256i ky = _mm256_andnot_si256(eq, _mm256_castpd_si256(my));
      const __m256i kz = _mm256_andnot_si256(eq, _mm256_castpd_si256(mz));
      i = _mm256_add_epi64(i, _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(sx, kx), _mm256_and_si256(sy, ky)),
                                              _mm256_and_si256(sz, kz)));
      rx = _mm256_add_epi64(rx, kx);
      ry = _mm256_add_epi64(ry, ky);
      rz = _mm256_add_epi64(rz, kz);
      budget = _mm256_add_epi64(budget, ones);
      const __m256i out = _mm256_or_si256(_mm256_or_si256(rx, ry), rz);  // sign: left the grid
      const __m256i over = _mm256_or_si256(_mm256_or_si256(eq, _mm256_cmpeq_epi64(budget, zero)), out);
      done = _mm256_movemask_pd(_mm256_castsi256_pd(over));
    }
    _mm256_store_pd(L.tx, tx), _mm256_store_pd(L.ty, ty), _mm256_store_pd(L.tz, tz);
    store(L.i, i), store(L.rx, rx), store(L.ry, ry), store(L.rz, rz), store(L.budget, budget);
    bool all_live = true;
    for (int k = 0; k < kVectorLanes; ++k) {
      if (!(done >> k & 1)) continue;
      L.get(k, w[k]);
      w[k].at_end = eqm >> k & 1;
      finish_walk(w[k], dims, box, hits);
      if (refill(k)) L.put(k, w[k]);
      else live[k] = all_live = false;
    }
    if (!all_live) {
      for (int k = 0; k < kVectorLanes; ++k)
        if (live[k] && !(done >> k & 1)) L.get(k, w[k]);
      return;
    }
  }
}
#endif

// Calls fn(row start index, x0, x1) for every x-row of the box, rows spread over threads.
template <typename Fn>
void for_box_rows(const TouchBox& box, const Dims& dims, int threads, Fn&& fn) {
  if (box.empty()) return;
  const std::size_t ny = static_cast<std::size_t>(box.hi[1] - box.lo[1] + 1);
  const std::size_t rows = ny * static_cast<std::size_t>(box.hi[2] - box.lo[2] + 1);
  const std::size_t x0 = static_cast<std::size_t>(box.lo[0]), x1 = static_cast<std::size_t>(box.hi[0]) + 1;
  parallel_for(rows, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) {
      const std::size_t y = static_cast<std::size_t>(box.lo[1]) + r % ny;
      const std::size_t z = static_cast<std::size_t>(box.lo[2]) + r / ny;
      fn((z * dims.ny + y) * dims.nx, x0, x1);
    }
  });
}

}  // namespace

void OccupancyFusion::insert_scan(const Vec3& sensor, const float* xyz, std::size_t count,
                                  std::size_t stride, int threads) {
  for (double s : sensor)
    if (!std::isfinite(s)) throw Error(Status::bad_value, "sensor origin is not finite");
  // marks_ is all zero between scans: the apply pass (or a cancel) clears what a scan set.
  const double maxr = model_.max_range;
  std::uint64_t used = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = xyz + i * stride;
    used += std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
  }
  const double vs = frame_.voxel_size;
  const double a[3] = {(sensor[0] - frame_.origin[0]) / vs, (sensor[1] - frame_.origin[1]) / vs,
                       (sensor[2] - frame_.origin[2]) / vs};
  std::uint8_t* marks = marks_.data();
  auto start = [&](std::size_t i, Walk& w, TouchBox& box) {
    const float* p = xyz + i * stride;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return false;
    Vec3 end{p[0], p[1], p[2]};
    bool hit = true;
    if (maxr >= 0) {
      const double dx = end[0] - sensor[0], dy = end[1] - sensor[1], dz = end[2] - sensor[2];
      const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (len > maxr) {  // a max-range return marks free space only
        const double s = maxr / len;
        end = {sensor[0] + dx * s, sensor[1] + dy * s, sensor[2] + dz * s};
        hit = false;
      }
    }
    double b[3];
    for (int k = 0; k < 3; ++k) b[k] = (end[k] - frame_.origin[k]) / vs;
    return start_walk(a, b, hit, frame_.dims, w, box);
  };
  // Walks rays [r, e) several at a time; a lane whose walk ends takes the next ray.
  constexpr int kLanes = 4;  // the SSE2 walk interleaves 4 rays
#ifdef OCCSEG_FUSION_AVX2
  constexpr int kSlots = kVectorLanes > kLanes ? kVectorLanes : kLanes;
  const bool avx2 = use_avx2();
#else
  constexpr int kSlots = kLanes;
  const bool avx2 = false;
#endif
  auto walk_rays = [&](std::size_t r, std::size_t e, TouchBox& box, std::vector<std::uint64_t>& hits) {
    Walk lanes[kSlots];
    bool busy[kSlots] = {};
    int active = 0;
    auto refill = [&](int k) {
      while (r < e)
        if (start(r++, lanes[k], box)) return true;
      return false;
    };
#ifdef OCCSEG_FUSION_AVX2
    if (avx2) {
      for (int k = 0; k < kVectorLanes; ++k) active += busy[k] = refill(k);
      if (active == kVectorLanes)
        walk_vector_avx2(lanes, busy, marks, frame_.dims, box, hits, refill);
      active = 0;  // the rest of the walks finish one by one below
    }
#endif
    if (!avx2) {
      for (int k = 0; k < kLanes; ++k) active += busy[k] = refill(k);
      while (active == kLanes) {
        for (int k = 0; k < kLanes; ++k)
          if (!step(lanes[k], marks)) {
            finish_walk(lanes[k], frame_.dims, box, hits);
            if (!refill(k)) {
              busy[k] = false;
              --active;
            }
          }
      }
    }
    for (int k = 0; k < kSlots; ++k)  // the last few walks, one by one
      if (busy[k]) {
        while (step(lanes[k], marks)) {
        }
        finish_walk(lanes[k], frame_.dims, box, hits);
      }
  };
  TouchBox box;
  std::vector<std::uint64_t> hits;  // end voxels holding a return, written after the walks
  std::mutex box_mutex;
  // With a progress callback rays go in chunks, so long scans report; marks only ever grow, so
  // the chunking changes nothing in the result.
  const std::size_t chunk = progress_ ? std::size_t(1) << 16 : std::max<std::size_t>(count, 1);
  for (std::size_t c0 = 0; c0 < count; c0 += chunk) {
    const std::size_t c1 = std::min(count, c0 + chunk);
    // Threads take blocks of rays from a shared counter: ray lengths vary across a cloud (floor
    // near, wall far), so fixed halves left one thread idle. Marks only ever grow, so which
    // thread walks which ray changes nothing.
    constexpr std::size_t kBlock = 2048;
    const std::size_t blocks = (c1 - c0 + kBlock - 1) / kBlock;
    std::atomic<std::size_t> next{0};
    parallel_for(std::min<std::size_t>(blocks, resolve_threads(threads)), threads, [&](std::size_t, std::size_t) {
      TouchBox mine;
      std::vector<std::uint64_t> my_hits;
      for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < blocks;)
        walk_rays(c0 + k * kBlock, std::min(c1, c0 + (k + 1) * kBlock), mine, my_hits);
      std::lock_guard<std::mutex> lock(box_mutex);
      box.merge(mine);
      hits.insert(hits.end(), my_hits.begin(), my_hits.end());
    });
    // Hits go in once every walk of the chunk is over: a concurrent "crossed" mark could have
    // overwritten them (it stores without a locked read-modify-write).
    for (std::uint64_t h : hits) marks[h] = 2;
    hits.clear();
    if (progress_ && !progress_(c1, count)) {
      for_box_rows(box, frame_.dims, threads, [&](std::size_t row, std::size_t x0, std::size_t x1) {
        std::fill(marks + row + x0, marks + row + x1, std::uint8_t(0));
      });
      throw Error(Status::cancelled, "ray casting cancelled by the progress callback");
    }
  }
  const float lh = l_hit_, lm = l_miss_, lo = l_min_, hi = l_max_;
  float* lodds = log_odds_.data();
  for_box_rows(box, frame_.dims, threads, [&](std::size_t row, std::size_t x0, std::size_t x1) {
    std::uint8_t* m = marks + row;
    float* l = lodds + row;
    for (std::size_t x = x0; x < x1; ++x) {
      if (x % 8 == 0 && x + 8 <= x1) {  // skip 8 unmarked voxels at a time
        std::uint64_t w;
        std::memcpy(&w, m + x, 8);
        if (w == 0) {
          x += 7;
          continue;
        }
      }
      const std::uint8_t v = m[x];
      if (!v) continue;
      l[x] = std::clamp(l[x] + ((v & 2) ? lh : lm), lo, hi);
      m[x] = 0;
    }
  });
  ++scans_;
  rays_ += used;
}

void OccupancyFusion::insert_scan(const Vec3& sensor, const std::vector<Vec3>& endpoints, int threads) {
  std::vector<float> xyz(endpoints.size() * 3);
  for (std::size_t i = 0; i < endpoints.size(); ++i)
    for (int k = 0; k < 3; ++k) xyz[3 * i + k] = static_cast<float>(endpoints[i][k]);
  insert_scan(sensor, xyz.data(), endpoints.size(), 3, threads);
}

Grid OccupancyFusion::grid() const {
  Grid g;
  g.dims = frame_.dims;
  g.voxel_size = frame_.voxel_size;
  g.origin = frame_.origin;
  g.p.resize(log_odds_.size());
  for (std::size_t i = 0; i < log_odds_.size(); ++i) {
    const float l = log_odds_[i];
    g.p[i] = l == 0.0f ? 0.5f : static_cast<float>(1.0 / (1.0 + std::exp(-static_cast<double>(l))));
  }
  return g;
}

GridFrame fit_frame(const std::vector<Vec3>& points, double voxel_size, double margin) {
  if (!(voxel_size > 0)) throw Error(Status::bad_value, "voxel size must be positive");
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi{-lo[0], -lo[1], -lo[2]};
  std::size_t used = 0;
  for (const Vec3& p : points) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    ++used;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  }
  if (!used) throw Error(Status::bad_value, "no finite point to fit a grid to");
  GridFrame f;
  f.voxel_size = voxel_size;
  std::size_t n[3];
  for (int k = 0; k < 3; ++k) {
    const double a = std::floor((lo[k] - margin) / voxel_size), b = std::floor((hi[k] + margin) / voxel_size) + 1;
    // Far from the world origin b - a can round to 0 (floor(x) + 1 == floor(x)): out of range.
    if (!(b - a >= 1))
      throw Error(Status::bad_value, "points this far from the world origin are out of range for voxels of " +
                                         std::to_string(voxel_size) + " m");
    if (!(b - a <= double(kMaxVoxels)))
      throw Error(Status::bad_dims, "points span " + std::to_string((b - a) * voxel_size) +
                                        " m: too many voxels of " + std::to_string(voxel_size) + " m");
    f.origin[k] = a * voxel_size;
    n[k] = static_cast<std::size_t>(b - a);
  }
  f.dims = Dims{n[0], n[1], n[2]};
  check_dims(f.dims);
  return f;
}

}  // namespace occseg
