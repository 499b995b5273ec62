#include <gtest/gtest.h>

#include <cmath>

#include "stages/histogram.hpp"

using namespace occseg;

namespace {
// Eq. (1) written out term by term, independently of the library's loop.
double g_direct(const Histogram& s, const Histogram& m) {
  auto fl = [](double f) { return f > 0 ? f * std::log(f) : 0.0; };
  double t1 = 0, ns = 0, nm = 0, t3 = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    t1 += fl(s[i]) + fl(m[i]);
    ns += s[i];
    nm += m[i];
    t3 += fl(double(s[i]) + m[i]);
  }
  const double t2 = fl(ns) + fl(nm), t4 = fl(ns + nm);
  return 2 * t1 - 2 * t2 - 2 * t3 + 2 * t4;
}
}  // namespace

TEST(GStatistic, MatchesDirectFormula) {
  Histogram s(512, 0), m(512, 0);
  for (int i = 0; i < 512; ++i) {
    s[i] = (i * 7) % 13;
    m[i] = (i * 5 + 3) % 11;
  }
  EXPECT_NEAR(g_statistic(s, m), g_direct(s, m), 1e-9 * g_direct(s, m));
}

TEST(GStatistic, HandComputedTwoBins) {
  // s = (10, 0), m = (0, 10): G = 2[2*10 ln10 - 2*10 ln10 - 2*10 ln10 + 20 ln20] = 40 ln 2.
  Histogram s{10, 0}, m{0, 10};
  EXPECT_NEAR(g_statistic(s, m), 40 * std::log(2.0), 1e-9);
}

TEST(GStatistic, ProportionalHistogramsGiveZero) {
  Histogram s{3, 5, 0, 7}, m{6, 10, 0, 14};
  EXPECT_EQ(g_statistic(s, m), 0.0);
  EXPECT_EQ(g_statistic(s, s), 0.0);
}

TEST(GStatistic, GrowsWithDifference) {
  Histogram a{50, 50}, b{60, 40}, c{90, 10};
  EXPECT_LT(g_statistic(a, b), g_statistic(a, c));
  EXPECT_GT(g_statistic(a, b), 0.0);
}
