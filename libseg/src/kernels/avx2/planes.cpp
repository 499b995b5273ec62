// The support planes' AVX2 kernels: four points of a plane search's sample, or eight labels of a
// row, per instruction.
#include "kernels/planes_levels.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace occseg::kernels::avx2 {

namespace {

// The terms of points i .. i + 3 of plane (n0, n1, n2, d: its coefficients in every lane): the
// same operations in the same order per point as the scalar cost (no FMA, which would round
// differently).
__attribute__((target("avx2"))) inline __m256d terms4(const PlanePoints& c, std::size_t i, __m256d n0, __m256d n1,
                                                      __m256d n2, __m256d d, __m256d cap) {
  __m256d t = _mm256_add_pd(_mm256_mul_pd(n0, _mm256_loadu_pd(c.x + i)), _mm256_mul_pd(n1, _mm256_loadu_pd(c.y + i)));
  t = _mm256_sub_pd(_mm256_add_pd(t, _mm256_mul_pd(n2, _mm256_loadu_pd(c.z + i))), d);
  // std::min(e * e, cap) is cap < e * e ? cap : e * e; minpd(a, b) is a < b ? a : b
  return _mm256_min_pd(_mm256_mul_pd(t, t), cap);
}

__attribute__((target("avx2"))) inline double lane_sum(__m256d acc) {
  double l[4];
  _mm256_storeu_pd(l, acc);
  return (l[0] + l[1]) + (l[2] + l[3]);
}

// The cost from point i on (a multiple of kMsacChunk, or n & ~3), with the lanes' sums so far in
// `acc`: lane j of the vector is lane j of the scalar cost.
__attribute__((target("avx2"))) double cost_from(const PlanePoints& c, const MsacPlane& pl, double cap, double stop,
                                                 __m256d acc, std::size_t i) {
  const __m256d n0 = _mm256_set1_pd(pl.n0), n1 = _mm256_set1_pd(pl.n1), n2 = _mm256_set1_pd(pl.n2);
  const __m256d d = _mm256_set1_pd(pl.d), vcap = _mm256_set1_pd(cap);
  const std::size_t n = c.n, n4 = n & ~std::size_t(3);
  while (i < n4) {
    for (const std::size_t e = std::min(n4, i + kMsacChunk); i < e; i += 4)
      acc = _mm256_add_pd(acc, terms4(c, i, n0, n1, n2, d, vcap));
    if (lane_sum(acc) >= stop) return lane_sum(acc);
  }
  double l[4];
  _mm256_storeu_pd(l, acc);
  for (; i < n; ++i) {
    const double e = pl.n0 * c.x[i] + pl.n1 * c.y[i] + pl.n2 * c.z[i] - pl.d;
    l[i % 4] += std::min(e * e, cap);
  }
  return (l[0] + l[1]) + (l[2] + l[3]);
}

}  // namespace

__attribute__((target("avx2"))) double planes_cost(const PlanePoints& pts, const MsacPlane& pl, double cap,
                                                   double stop) {
  return cost_from(pts, pl, cap, stop, _mm256_setzero_pd(), 0);
}

// A plane's sums are one chain of additions (4 cycles per 4 points), so two chains side by side
// score twice the planes in the same time. A plane that reaches `stop` drops out, the other goes
// on alone.
__attribute__((target("avx2"))) void planes_cost_pair(const PlanePoints& c, const MsacPlane& a, const MsacPlane& b,
                                                      double cap, double stop, double& cost_a, double& cost_b) {
  const __m256d a0 = _mm256_set1_pd(a.n0), a1 = _mm256_set1_pd(a.n1), a2 = _mm256_set1_pd(a.n2);
  const __m256d b0 = _mm256_set1_pd(b.n0), b1 = _mm256_set1_pd(b.n1), b2 = _mm256_set1_pd(b.n2);
  const __m256d ad = _mm256_set1_pd(a.d), bd = _mm256_set1_pd(b.d), vcap = _mm256_set1_pd(cap);
  const std::size_t n4 = c.n & ~std::size_t(3);
  __m256d acc_a = _mm256_setzero_pd(), acc_b = _mm256_setzero_pd();
  std::size_t i = 0;
  while (i < n4) {
    for (const std::size_t e = std::min(n4, i + kMsacChunk); i < e; i += 4) {
      acc_a = _mm256_add_pd(acc_a, terms4(c, i, a0, a1, a2, ad, vcap));
      acc_b = _mm256_add_pd(acc_b, terms4(c, i, b0, b1, b2, bd, vcap));
    }
    const bool out_a = lane_sum(acc_a) >= stop, out_b = lane_sum(acc_b) >= stop;
    if (out_a || out_b) {
      cost_a = out_a ? lane_sum(acc_a) : cost_from(c, a, cap, stop, acc_a, i);
      cost_b = out_b ? lane_sum(acc_b) : cost_from(c, b, cap, stop, acc_b, i);
      return;
    }
  }
  cost_a = cost_from(c, a, cap, stop, acc_a, i);  // (the last n % 4 points)
  cost_b = cost_from(c, b, cap, stop, acc_b, i);
}

// Lane k of kCompress[m]: the k-th set bit of the 4-bit mask m (the lanes past its count: 0).
alignas(16) constexpr std::uint32_t kCompress[16][4] = {
    {0, 0, 0, 0}, {0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0}, {2, 0, 0, 0}, {0, 2, 0, 0}, {1, 2, 0, 0}, {0, 1, 2, 0},
    {3, 0, 0, 0}, {0, 3, 0, 0}, {1, 3, 0, 0}, {0, 1, 3, 0}, {2, 3, 0, 0}, {0, 2, 3, 0}, {1, 2, 3, 0}, {0, 1, 2, 3}};

// The four positions of a vector's inliers are stored at once: out[count .. count + 4) is within
// out[0 .. n) because count <= i and i + 4 <= n.
__attribute__((target("avx2,popcnt"))) double planes_cost_inliers(const PlanePoints& c, const MsacPlane& pl,
                                                                   double cap, double stop, double inlier,
                                                                   std::uint32_t* out, std::size_t& count) {
  const __m256d n0 = _mm256_set1_pd(pl.n0), n1 = _mm256_set1_pd(pl.n1), n2 = _mm256_set1_pd(pl.n2);
  const __m256d d = _mm256_set1_pd(pl.d), vcap = _mm256_set1_pd(cap), vin = _mm256_set1_pd(inlier);
  const __m256d sign = _mm256_set1_pd(-0.0);
  const std::size_t n = c.n, n4 = n & ~std::size_t(3);
  __m256d acc = _mm256_setzero_pd();
  std::size_t k = 0, i = 0;
  while (i < n4) {
    for (const std::size_t e = std::min(n4, i + kMsacChunk); i < e; i += 4) {
      __m256d t =
          _mm256_add_pd(_mm256_mul_pd(n0, _mm256_loadu_pd(c.x + i)), _mm256_mul_pd(n1, _mm256_loadu_pd(c.y + i)));
      t = _mm256_sub_pd(_mm256_add_pd(t, _mm256_mul_pd(n2, _mm256_loadu_pd(c.z + i))), d);
      acc = _mm256_add_pd(acc, _mm256_min_pd(_mm256_mul_pd(t, t), vcap));
      const int m = _mm256_movemask_pd(_mm256_cmp_pd(_mm256_andnot_pd(sign, t), vin, _CMP_LE_OQ));
      const __m128i at = _mm_add_epi32(_mm_set1_epi32(static_cast<int>(i)),
                                       _mm_load_si128(reinterpret_cast<const __m128i*>(kCompress[m])));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + k), at);
      k += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(m)));
    }
    if (lane_sum(acc) >= stop) return lane_sum(acc);
  }
  double l[4];
  _mm256_storeu_pd(l, acc);
  for (; i < n; ++i) {
    const double e = pl.n0 * c.x[i] + pl.n1 * c.y[i] + pl.n2 * c.z[i] - pl.d;
    l[i % 4] += std::min(e * e, cap);
    out[k] = static_cast<std::uint32_t>(i);
    k += std::fabs(e) <= inlier;
  }
  count = k;
  return (l[0] + l[1]) + (l[2] + l[3]);
}

__attribute__((target("avx2,popcnt"))) std::size_t planes_row_members(const std::uint32_t* row, std::size_t x0,
                                                                       std::size_t x1, std::uint32_t s,
                                                                       std::uint64_t* bits) {
  const __m256i v = _mm256_set1_epi32(static_cast<int>(s));
  std::size_t count = 0;
  for (std::size_t k = 0; x0 + k < x1; k += 64) {
    std::uint64_t w = 0;
    std::size_t j = 0;
    for (; j < 64 && x0 + k + j + 8 <= x1; j += 8) {
      const __m256i l = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x0 + k + j));
      const auto m = static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(l, v))));
      w |= static_cast<std::uint64_t>(m) << j;
    }
    for (; j < 64 && x0 + k + j < x1; ++j) w |= static_cast<std::uint64_t>(row[x0 + k + j] == s) << j;
    bits[k / 64] = w;
    count += static_cast<std::size_t>(__builtin_popcountll(w));
  }
  return count;
}

}  // namespace occseg::kernels::avx2

#endif
