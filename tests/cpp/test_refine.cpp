#include <gtest/gtest.h>

#include "stages/refine.hpp"

using namespace occseg;

namespace {
constexpr std::uint8_t F = 0, U = 1, O = 2;

// A 1 x 1 x n line map: scans along x only see one voxel, so only the z scans act.
Grid line(const std::vector<float>& p) {
  Grid g(Dims{1, 1, p.size()}, 0.5f);
  g.p = p;
  return g;
}
}  // namespace

TEST(Refine, FourCasesFreeToOccupied) {
  Params prm;
  bool re[3];
  const float all_half[3] = {0.5f, 0.5f, 0.5f};
  classify_window(all_half, 3, F, O, prm, re);  // case i
  EXPECT_FALSE(re[0] || re[1] || re[2]);
  const float own[3] = {0.5f, 0.9f, 0.5f};
  classify_window(own, 3, F, O, prm, re);  // case ii
  EXPECT_FALSE(re[0] || re[1] || re[2]);
  const float other[3] = {0.5f, 0.2f, 0.5f};
  classify_window(other, 3, F, O, prm, re);  // case iii: all three move
  EXPECT_TRUE(re[0] && re[1] && re[2]);
  const float mixed[3] = {0.2f, 0.9f, 0.5f};
  classify_window(mixed, 3, F, O, prm, re);  // case iv: <= 0.5 moves
  EXPECT_TRUE(re[0]);
  EXPECT_FALSE(re[1]);
  EXPECT_TRUE(re[2]);
}

TEST(Refine, FourCasesOccupiedToFree) {
  Params prm;
  bool re[3];
  const float own[3] = {0.1f, 0.5f, 0.5f};
  classify_window(own, 3, O, F, prm, re);  // case ii
  EXPECT_FALSE(re[0] || re[1] || re[2]);
  const float other[3] = {0.5f, 0.5f, 0.8f};
  classify_window(other, 3, O, F, prm, re);  // case iii
  EXPECT_TRUE(re[0] && re[1] && re[2]);
  const float mixed[3] = {0.1f, 0.5f, 0.8f};
  classify_window(mixed, 3, O, F, prm, re);  // case iv: >= 0.5 moves
  EXPECT_FALSE(re[0]);
  EXPECT_TRUE(re[1]);
  EXPECT_TRUE(re[2]);
}

TEST(Refine, BoundaryScanMovesThreeVoxels) {
  // Free segment then an occupied segment whose first three voxels are free-valued.
  const Grid g = line({0.2f, 0.2f, 0.2f, 0.3f, 0.5f, 0.9f, 0.9f, 0.9f});
  std::vector<std::uint8_t> st{F, F, F, O, O, O, O, O};
  Params prm;
  prm.refine_passes = 1;
  refine_boundaries(st, g, prm);
  // z+ scan: boundary at 3, window {0.3, 0.5, 0.9} mixed -> 3 and 4 become free.
  EXPECT_EQ(st, (std::vector<std::uint8_t>{F, F, F, F, F, O, O, O}));
}

TEST(Refine, UnknownGrowsOverHalfVoxelsUntilAnotherValue) {
  const Grid g = line({0.5f, 0.5f, 0.5f, 0.5f, 0.3f, 0.5f, 0.2f});
  std::vector<std::uint8_t> st{U, U, F, F, F, F, F};
  refine_unknown(st, g, Params());
  EXPECT_EQ(st, (std::vector<std::uint8_t>{U, U, U, U, F, F, F}));
  // Backward scan: from the other end there is no unknown segment before the free one.
  const Grid h = line({0.2f, 0.5f, 0.5f, 0.5f});
  std::vector<std::uint8_t> s2{F, F, F, U};
  refine_unknown(s2, h, Params());
  EXPECT_EQ(s2, (std::vector<std::uint8_t>{F, U, U, U}));
}
