#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "occseg/sim/random.hpp"

using namespace occseg::sim;

TEST(SimRandom, UniformIsTheStandardEngineScaled) {
  // The standard fixes mt19937_64: its 10000th output from the default seed is 9981545732273789042.
  std::mt19937_64 ref;
  ref.discard(9999);
  EXPECT_EQ(ref(), 9981545732273789042ULL);
  std::mt19937_64 e(42);
  Rng r(42);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(r.uniform(), double(e() >> 11) / 9007199254740992.0);
}

TEST(SimRandom, GaussianHasUnitMomentsAndIsRepeatable) {
  Rng r(7);
  const int n = 200000;
  double s = 0, s2 = 0, s4 = 0;
  for (int i = 0; i < n; ++i) {
    const double g = r.gaussian();
    s += g;
    s2 += g * g;
    s4 += g * g * g * g;
  }
  const double mean = s / n, var = s2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.0, 4.0 / std::sqrt(n));   // 4 standard errors
  EXPECT_NEAR(var, 1.0, 4.0 * std::sqrt(2.0 / n));
  EXPECT_NEAR(s4 / n, 3.0, 0.06);                // kurtosis of a normal
  Rng a(123), b(123);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(a.gaussian(), b.gaussian());
}

TEST(SimRandom, MixSeedSeparatesStreams) {
  EXPECT_EQ(mix_seed(1, 2, 3), mix_seed(1, 2, 3));
  EXPECT_NE(mix_seed(1, 2, 3), mix_seed(1, 3, 2));
  EXPECT_NE(mix_seed(1, 2, 3), mix_seed(2, 2, 3));
  EXPECT_NE(mix_seed(0, 0, 0), 0u);
}
