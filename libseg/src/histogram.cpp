#include "occseg/histogram.hpp"

#include <cmath>

namespace occseg {

namespace {
inline double xlogx(double v) { return v > 0 ? v * std::log(v) : 0.0; }
}  // namespace

double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins) {
  // Fixed summation (docs/algorithm.md, section 2): each histogram's sum f ln f on its own, in bin
  // order, so that division can compute it once per histogram instead of once per pair; the
  // joint term in bin order. Terms of empty bins are exact zeros and change nothing.
  double cells_s = 0, cells_m = 0, joint = 0, ns = 0, nm = 0;
  for (std::size_t i = 0; i < bins; ++i) {
    const double a = s[i], b = m[i];
    if (a == 0 && b == 0) continue;
    cells_s += xlogx(a);
    cells_m += xlogx(b);
    joint += xlogx(a + b);
    ns += a;
    nm += b;
  }
  const double cells = cells_s + cells_m;
  const double g = 2.0 * (cells - xlogx(ns) - xlogx(nm) - joint + xlogx(ns + nm));
  // Proportional histograms give exactly 0 in exact arithmetic but +-1e-10 here; without this
  // cut, Gmin = 1e-10 would make every ratio Gmax / Gmin look huge.
  return g > 1e-9 * (ns + nm) ? g : 0.0;
}

}  // namespace occseg
