// The support planes' kernels in plain C++: the meaning every other level's kernels are tested
// against.
#include <algorithm>
#include <cmath>

#include "kernels/planes_levels.hpp"

namespace occseg::kernels::scalar {

double planes_cost(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop) {
  double l[4] = {0, 0, 0, 0};
  for (std::size_t b = 0; b < pts.n; b += kMsacChunk) {
    for (std::size_t i = b; i < std::min(pts.n, b + kMsacChunk); ++i) {
      const double e = pl.n0 * pts.x[i] + pl.n1 * pts.y[i] + pl.n2 * pts.z[i] - pl.d;
      l[i % 4] += std::min(e * e, cap);
    }
    if ((l[0] + l[1]) + (l[2] + l[3]) >= stop) break;
  }
  return (l[0] + l[1]) + (l[2] + l[3]);
}

void planes_cost_pair(const PlanePoints& pts, const MsacPlane& a, const MsacPlane& b, double cap, double stop,
                      double& cost_a, double& cost_b) {
  cost_a = planes_cost(pts, a, cap, stop);
  cost_b = planes_cost(pts, b, cap, stop);
}

double planes_cost_inliers(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop, double inlier,
                           std::uint32_t* out, std::size_t& count) {
  double l[4] = {0, 0, 0, 0};
  std::size_t c = 0;
  for (std::size_t b = 0; b < pts.n; b += kMsacChunk) {
    for (std::size_t i = b; i < std::min(pts.n, b + kMsacChunk); ++i) {
      const double e = pl.n0 * pts.x[i] + pl.n1 * pts.y[i] + pl.n2 * pts.z[i] - pl.d;
      l[i % 4] += std::min(e * e, cap);
      out[c] = static_cast<std::uint32_t>(i);  // (without a branch per point)
      c += std::fabs(e) <= inlier;
    }
    if ((l[0] + l[1]) + (l[2] + l[3]) >= stop) break;
  }
  count = c;
  return (l[0] + l[1]) + (l[2] + l[3]);
}

std::size_t planes_row_members(const std::uint32_t* row, std::size_t x0, std::size_t x1, std::uint32_t s,
                               std::uint64_t* bits) {
  std::size_t count = 0;
  for (std::size_t k = 0; x0 + k < x1; k += 64) {
    std::uint64_t w = 0;
    for (std::size_t j = 0; j < 64 && x0 + k + j < x1; ++j)
      w |= static_cast<std::uint64_t>(row[x0 + k + j] == s) << j;
    bits[k / 64] = w;
    count += static_cast<std::size_t>(__builtin_popcountll(w));
  }
  return count;
}

}  // namespace occseg::kernels::scalar
