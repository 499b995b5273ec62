#include <gtest/gtest.h>

#include "occseg/create.hpp"

using namespace occseg;

TEST(Create, MopAndStateIntervals) {
  Grid g(Dims{4, 2, 1}, 0.0f);
  // Left 2x2 block: mean 0.5 (unknown); right 2x2 block: mean 0.503 (occupied).
  g.at(0, 0, 0) = 0.4f; g.at(1, 0, 0) = 0.6f; g.at(0, 1, 0) = 0.5f; g.at(1, 1, 0) = 0.5f;
  g.at(2, 0, 0) = 0.503f; g.at(3, 0, 0) = 0.503f; g.at(2, 1, 0) = 0.503f; g.at(3, 1, 0) = 0.503f;
  Block l{{0, 0, 0}, {2, 2, 1}}, r{{2, 0, 0}, {4, 2, 1}};
  EXPECT_NEAR(mean_occupancy(g, l), 0.5, 1e-7);
  const auto st = create_segments(g, {l, r}, Params());
  EXPECT_EQ(st[g.index(0, 0, 0)], 1);  // unknown although the voxel itself is 0.4
  EXPECT_EQ(st[g.index(3, 1, 0)], 2);
  Params p;
  EXPECT_EQ(p.state_of(0.4979), State::free);
  EXPECT_EQ(p.state_of(0.498), State::unknown);
  EXPECT_EQ(p.state_of(0.502), State::unknown);
  EXPECT_EQ(p.state_of(0.5021), State::occupied);
}
