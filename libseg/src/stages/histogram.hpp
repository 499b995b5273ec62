// Stage 2 (section 2.3): LBP/C histograms and the G-statistic of equation (1).
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occseg {

using Histogram = std::vector<std::uint32_t>;  // 64 x b bins, index = lbp * b + contrast level

// k ln k for a count k, 0 ln 0 = 0: looked up below 2^16 (a block of up to 32^3 voxels), computed
// above, the same expression either way.
class XLogX {
 public:
  XLogX() : t_(kSize) {
    t_[0] = 0.0;
    for (std::size_t k = 1; k < kSize; ++k) t_[k] = static_cast<double>(k) * std::log(static_cast<double>(k));
  }
  double operator()(std::uint64_t k) const {
    if (k < kSize) return t_[k];
    const double v = static_cast<double>(k);
    return v * std::log(v);
  }

 private:
  static constexpr std::size_t kSize = std::size_t(1) << 16;
  std::vector<double> t_;
};

// The one table (built on first use).
const XLogX& xlogx_table();

// One of the sums of eq. (1) in its documented order (docs/algorithm.md, section 2): the terms
// xl(v[k]) of the listed counts v[0..n), the k-th into lane k % 8, the lanes added as
// ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)). Eight independent chains of additions.
template <class Count>
inline double lane_sum(const XLogX& xl, const Count* v, std::size_t n) {
  double l0 = 0, l1 = 0, l2 = 0, l3 = 0, l4 = 0, l5 = 0, l6 = 0, l7 = 0;
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) {
    l0 += xl(v[k]);
    l1 += xl(v[k + 1]);
    l2 += xl(v[k + 2]);
    l3 += xl(v[k + 3]);
    l4 += xl(v[k + 4]);
    l5 += xl(v[k + 5]);
    l6 += xl(v[k + 6]);
    l7 += xl(v[k + 7]);
  }
  double l[8] = {l0, l1, l2, l3, l4, l5, l6, l7};
  for (; k < n; ++k) l[k % 8] += xl(v[k]);
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

// What eq. (1) needs of one histogram on its own: its total, and its sum f ln f (lane_sum of its
// non-empty bins in bin order). The division computes them once per histogram, not once per pair.
struct HistogramSums {
  std::uint64_t n = 0;
  double cells = 0;
};

// Eq. (1) from its sums, `joint` being lane_sum of f_s + f_m over the bins where either histogram
// is non-empty, in bin order:
//   G = 2 [ cells_s + cells_m - n_s ln n_s - n_m ln n_m - joint + N ln N ],   N = n_s + n_m.
// Proportional histograms give exactly 0 in exact arithmetic but about +-1e-10 N here; values
// below 1e-9 N are 0, else Gmin = 1e-10 would make every ratio Gmax / Gmin look huge.
inline double g_from_sums(const XLogX& xl, const HistogramSums& s, const HistogramSums& m, double joint) {
  const double ns = static_cast<double>(s.n), nm = static_cast<double>(m.n);
  const double cells = s.cells + m.cells;
  const double g = 2.0 * (cells - xl(s.n) - xl(m.n) - joint + xl(s.n + m.n));
  return g > 1e-9 * (ns + nm) ? g : 0.0;
}

// G = 2 [ sum_{s,m} sum_i f ln f  -  sum_{s,m} (sum_i f) ln(sum_i f)
//         - sum_i (f_s + f_m) ln(f_s + f_m)  +  N ln N ],   N = total count of both, 0 ln 0 = 0.
// Zero when the two histograms are proportional; larger the more they differ. Lists the non-empty
// bins and evaluates them with lane_sum and g_from_sums, as the division does with its kernels'
// lists, so the value is the same bit for bit wherever it is computed.
double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins);
inline double g_statistic(const Histogram& s, const Histogram& m) {
  return g_statistic(s.data(), m.data(), s.size() < m.size() ? s.size() : m.size());
}

}  // namespace occseg
