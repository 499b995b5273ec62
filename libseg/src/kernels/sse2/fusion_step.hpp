// The SSE2 step of a ray walk (kernels/fusion.hpp), for the SSE2 walk and the AVX2 walk's last
// rays.
#pragma once
#include <emmintrin.h>

#include "kernels/generic/fusion_walk.hpp"

namespace occseg::kernels {
namespace {

// Marks the current voxel crossed and moves one voxel on; false when the walk is over (at_end
// tells whether it stopped on its end voxel). The axis is chosen with compare masks, not
// branches (the choice is a coin flip on oblique rays), and each tmax gets + tdelta or + 0.0,
// which leaves it unchanged (but for the sign of a zero, which no compare sees).
inline bool sse2_step(Walk& w, std::uint8_t* marks) {
  mark_crossed(marks + w.i);
  if (w.i == w.end) {
    w.at_end = true;
    return false;
  }
  const __m128d tx = _mm_load_pd(w.tx), ty = _mm_load_pd(w.ty), tz = _mm_load_pd(w.tz);
  // Same choice as tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2).
  const __m128d xy = _mm_cmplt_sd(tx, ty), xz = _mm_cmplt_sd(tx, tz), yz = _mm_cmplt_sd(ty, tz);
  const __m128d mx = _mm_and_pd(xy, xz), my = _mm_andnot_pd(xy, yz);
  const __m128d mz = _mm_andnot_pd(_mm_or_pd(mx, my), _mm_castsi128_pd(_mm_set1_epi32(-1)));
  _mm_store_pd(w.tx, _mm_add_sd(tx, _mm_and_pd(mx, _mm_load_pd(w.dx))));
  _mm_store_pd(w.ty, _mm_add_sd(ty, _mm_and_pd(my, _mm_load_pd(w.dy))));
  _mm_store_pd(w.tz, _mm_add_sd(tz, _mm_and_pd(mz, _mm_load_pd(w.dz))));
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

}  // namespace
}  // namespace occseg::kernels
