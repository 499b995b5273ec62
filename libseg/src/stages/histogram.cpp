#include "stages/histogram.hpp"

#include <cmath>

namespace occseg {

namespace {
inline double xlogx(double v) { return v > 0 ? v * std::log(v) : 0.0; }

// The k-th term of one of the sums (k counted from 0; empty bins have no term) goes into lane
// k % 8; the lanes are added as ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)).
class LaneSum {
 public:
  void add(double v) { l_[k_++ % 8] += v; }
  double total() const { return ((l_[0] + l_[1]) + (l_[2] + l_[3])) + ((l_[4] + l_[5]) + (l_[6] + l_[7])); }

 private:
  double l_[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  std::size_t k_ = 0;
};

}  // namespace

double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins) {
  // Fixed summation (docs/algorithm.md, section 2): each histogram's sum f ln f on its own, in bin
  // order, so that division can compute it once per histogram instead of once per pair; the
  // joint term in bin order; each of the three in eight lanes (LaneSum), as division adds them.
  LaneSum cells_s, cells_m, joint;
  double ns = 0, nm = 0;
  for (std::size_t i = 0; i < bins; ++i) {
    const double a = s[i], b = m[i];
    if (a == 0 && b == 0) continue;
    if (a != 0) cells_s.add(xlogx(a));
    if (b != 0) cells_m.add(xlogx(b));
    joint.add(xlogx(a + b));
    ns += a;
    nm += b;
  }
  const double cells = cells_s.total() + cells_m.total();
  const double g = 2.0 * (cells - xlogx(ns) - xlogx(nm) - joint.total() + xlogx(ns + nm));
  // Proportional histograms give exactly 0 in exact arithmetic but +-1e-10 here; without this
  // cut, Gmin = 1e-10 would make every ratio Gmax / Gmin look huge.
  return g > 1e-9 * (ns + nm) ? g : 0.0;
}

}  // namespace occseg
