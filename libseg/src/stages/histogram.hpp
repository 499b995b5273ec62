// Stage 2 (section 2.3): LBP/C histograms and the G-statistic of equation (1).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occseg {

using Histogram = std::vector<std::uint32_t>;  // 64 x b bins, index = lbp * b + contrast level

// G = 2 [ sum_{s,m} sum_i f ln f  -  sum_{s,m} (sum_i f) ln(sum_i f)
//         - sum_i (f_s + f_m) ln(f_s + f_m)  +  N ln N ],   N = total count of both, 0 ln 0 = 0.
// Zero when the two histograms are proportional; larger the more they differ. The sums run in a
// fixed order (docs/algorithm.md, section 2: bin order, eight lanes), the division's included, so
// the value is the same bit for bit wherever it is computed.
double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins);
inline double g_statistic(const Histogram& s, const Histogram& m) {
  return g_statistic(s.data(), m.data(), s.size() < m.size() ? s.size() : m.size());
}

}  // namespace occseg
