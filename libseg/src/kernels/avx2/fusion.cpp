// The scan fusion's AVX2 ray walk: four rays in the four lanes of AVX2 registers, one step of
// each per iteration; the last rays of a block one by one with the SSE2 step.
#include "kernels/fusion_levels.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "kernels/sse2/fusion_step.hpp"

namespace occseg::kernels::avx2 {

namespace {

constexpr int kVectorLanes = 4;

struct alignas(32) Lanes {
  double tx[kVectorLanes], ty[kVectorLanes], tz[kVectorLanes], dx[kVectorLanes], dy[kVectorLanes], dz[kVectorLanes];
  std::int64_t i[kVectorLanes], end[kVectorLanes], sx[kVectorLanes], sy[kVectorLanes], sz[kVectorLanes];
  std::int64_t rx[kVectorLanes], ry[kVectorLanes], rz[kVectorLanes], budget[kVectorLanes];
  // Memory forms only: Valgrind (3.19) cannot decode the register form of VEX movq that
  // _mm_set_sd / _mm_cvtsd_f64 may compile to, and users run their programs under it.
  void put(int k, const Walk& w) {
    _mm_store_sd(tx + k, _mm_load_sd(w.tx)), _mm_store_sd(ty + k, _mm_load_sd(w.ty));
    _mm_store_sd(tz + k, _mm_load_sd(w.tz)), _mm_store_sd(dx + k, _mm_load_sd(w.dx));
    _mm_store_sd(dy + k, _mm_load_sd(w.dy)), _mm_store_sd(dz + k, _mm_load_sd(w.dz));
    i[k] = std::int64_t(w.i), end[k] = std::int64_t(w.end);
    sx[k] = std::int64_t(w.sx), sy[k] = std::int64_t(w.sy), sz[k] = std::int64_t(w.sz);
    rx[k] = w.rx, ry[k] = w.ry, rz[k] = w.rz, budget[k] = w.budget;
  }
  void get(int k, Walk& w) const {
    _mm_store_pd(w.tx, _mm_load_sd(tx + k)), _mm_store_pd(w.ty, _mm_load_sd(ty + k));
    _mm_store_pd(w.tz, _mm_load_sd(tz + k)), _mm_store_pd(w.dx, _mm_load_sd(dx + k));
    _mm_store_pd(w.dy, _mm_load_sd(dy + k)), _mm_store_pd(w.dz, _mm_load_sd(dz + k));
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

// The same IEEE operations as the SSE2 step (LT_OS compares, masked adds of tdelta), so the same
// voxels, at about a quarter of the instructions per voxel step (two groups of four lanes per
// iteration spill registers). Lanes go to memory only when one of them ends (about once per
// hundred steps). All lanes start live; `next(w[k])` starts the next ray in w[k] and returns
// false when there is none: then live[k] turns false and the function returns, leaving the walks
// still going in `w` for the SSE2 step to finish.
__attribute__((target("avx2"))) void walk_vector(Walk (&w)[kVectorLanes], bool (&live)[kVectorLanes],
                                                 std::uint8_t* marks, const Dims& dims, TouchBox& box,
                                                 std::vector<std::uint64_t>& hits, const NextRay& next) {
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
      // A lane at its end voxel is over (the step returns before moving); its tmax and index are
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
      if (next(w[k])) L.put(k, w[k]);
      else live[k] = all_live = false;
    }
    if (!all_live) {
      for (int k = 0; k < kVectorLanes; ++k)
        if (live[k] && !(done >> k & 1)) L.get(k, w[k]);
      return;
    }
  }
}

}  // namespace

void fusion_walk_rays(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                      std::vector<std::uint64_t>& hits) {
  Walk lanes[kVectorLanes];
  bool busy[kVectorLanes] = {};
  int active = 0;
  for (int k = 0; k < kVectorLanes; ++k) active += busy[k] = next(lanes[k]);
  if (active == kVectorLanes) walk_vector(lanes, busy, marks, dims, box, hits, next);
  for (int k = 0; k < kVectorLanes; ++k)  // the last few walks, one by one
    if (busy[k]) {
      while (sse2_step(lanes[k], marks)) {
      }
      finish_walk(lanes[k], dims, box, hits);
    }
}

}  // namespace occseg::kernels::avx2

#endif
