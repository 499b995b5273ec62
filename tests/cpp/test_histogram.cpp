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

// Each of the three sums of eq. (1) in the documented order: the k-th term of the non-empty bins
// into lane k % 8, the lanes added as ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)). Written
// out here from the text of docs/algorithm.md, compared bit for bit, for 0 to 60 non-empty bins.
TEST(GStatistic, SumsInTheDocumentedOrder) {
  auto fl = [](double f) { return f > 0 ? f * std::log(f) : 0.0; };
  for (int filled = 0; filled <= 60; ++filled) {
    Histogram s(128, 0), m(128, 0);
    for (int k = 0; k < filled; ++k) {
      // bins where only s, only m, or both are non-empty
      const int bin = 2 * k + (k % 3 == 0);
      if (k % 3 != 1) s[bin] = static_cast<std::uint32_t>(1 + (k * 37) % 101);
      if (k % 3 != 2) m[bin] = static_cast<std::uint32_t>(1 + (k * 53) % 89);
    }
    double lanes[3][8] = {};
    int count[3] = {0, 0, 0};
    double ns = 0, nm = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (s[i]) lanes[0][count[0]++ % 8] += fl(s[i]);
      if (m[i]) lanes[1][count[1]++ % 8] += fl(m[i]);
      if (s[i] || m[i]) lanes[2][count[2]++ % 8] += fl(double(s[i]) + m[i]);
      ns += s[i];
      nm += m[i];
    }
    double sum[3];
    for (int j = 0; j < 3; ++j) {
      const double* l = lanes[j];
      sum[j] = ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
    }
    const double g = 2.0 * ((sum[0] + sum[1]) - fl(ns) - fl(nm) - sum[2] + fl(ns + nm));
    EXPECT_EQ(g_statistic(s, m), g > 1e-9 * (ns + nm) ? g : 0.0) << filled << " bins";
  }
}

// Counts whose sum over both histograms needs more than 32 bits (allowed: a histogram holds
// uint32 counts): the joint term sees f_s + f_m, not its remainder modulo 2^32.
TEST(GStatistic, CountsBeyond32BitsOnceSummed) {
  Histogram s{0xFFFFFFF0u, 16}, m{16, 0xFFFFFFF0u};
  const double g = g_direct(s, m);
  EXPECT_GT(g, 1e9);
  EXPECT_NEAR(g_statistic(s, m), g, 1e-9 * g);
  Histogram p{0xFFFFFFFFu, 0}, q{0xFFFFFFFFu, 0};
  EXPECT_EQ(g_statistic(p, q), 0.0);
}
