// Stage 2 (section 2.3): the G-statistic of equation (1) between two histograms.
#include "stages/histogram.hpp"

namespace occseg {

const XLogX& xlogx_table() {
  static const XLogX t;
  return t;
}

double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins) {
  // The non-empty bins of s, of m, and of either (their sum, which may exceed 32 bits), in bin order.
  thread_local std::vector<std::uint64_t> list;
  list.resize(3 * bins);
  std::uint64_t* const vs = list.data();
  std::uint64_t* const vm = vs + bins;
  std::uint64_t* const vj = vm + bins;
  std::size_t ks = 0, km = 0, kj = 0;
  HistogramSums hs, hm;
  for (std::size_t i = 0; i < bins; ++i) {
    if (s[i] != 0) vs[ks++] = s[i];
    if (m[i] != 0) vm[km++] = m[i];
    if (s[i] != 0 || m[i] != 0) vj[kj++] = std::uint64_t(s[i]) + m[i];
    hs.n += s[i];
    hm.n += m[i];
  }
  const XLogX& xl = xlogx_table();
  hs.cells = lane_sum(xl, vs, ks);
  hm.cells = lane_sum(xl, vm, km);
  return g_from_sums(xl, hs, hm, lane_sum(xl, vj, kj));
}

}  // namespace occseg
