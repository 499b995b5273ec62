#include <gtest/gtest.h>

#include "occseg/departures.hpp"

using namespace occseg;

TEST(Departures, ThinGapsAreNotUnknownRegions) {
  Grid g(Dims{20, 20, 20}, 0.2f);
  // A 1-voxel-thick sheet of 0.5 (a gap between rays) and a 4x4x4 unknown cube.
  for (int z = 0; z < 20; ++z)
    for (int y = 0; y < 20; ++y) g.at(3, y, z) = 0.5f;
  for (int z = 10; z < 14; ++z)
    for (int y = 10; y < 14; ++y)
      for (int x = 10; x < 14; ++x) g.at(x, y, z) = 0.5f;
  const auto m = unknown_regions(g, Params());
  EXPECT_EQ(m[g.index(3, 5, 5)], 0);
  for (int z = 10; z < 14; ++z)
    for (int y = 10; y < 14; ++y)
      for (int x = 10; x < 14; ++x) EXPECT_EQ(m[g.index(x, y, z)], 1);
  EXPECT_EQ(m[g.index(9, 10, 10)], 0);
  EXPECT_EQ(m[g.index(14, 13, 13)], 0);
}

TEST(Departures, RegionAtTheMapEdgeSurvives) {
  Grid g(Dims{10, 10, 10}, 0.2f);
  for (int z = 0; z < 10; ++z)
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 2; ++x) g.at(x, y, z) = 0.5f;  // 2 thick, cut by the edge
  const auto m = unknown_regions(g, Params());
  EXPECT_EQ(m[g.index(0, 0, 0)], 1);
  EXPECT_EQ(m[g.index(1, 9, 9)], 1);
  EXPECT_EQ(m[g.index(2, 5, 5)], 0);
}

TEST(Departures, VoxelRules) {
  Grid g(Dims{5, 1, 1}, 0.2f);
  g.p = {0.9f, 0.5f, 0.2f, 0.5f, 0.2f};
  Params prm;
  // Texture says free everywhere; the occupied voxel stays occupied, the gap next to it becomes
  // unknown, the free-surrounded gap stays free.
  std::vector<std::uint8_t> st(5, 0);
  apply_voxel_rules(st, g, prm);
  EXPECT_EQ(st, (std::vector<std::uint8_t>{2, 1, 0, 0, 0}));
  // Texture says occupied: a free-valued voxel is free, a gap keeps the texture's state.
  std::vector<std::uint8_t> so(5, 2);
  apply_voxel_rules(so, g, prm);
  EXPECT_EQ(so, (std::vector<std::uint8_t>{2, 2, 0, 2, 0}));
}

TEST(Departures, GapConnectedToAnObjectIsNeverFree) {
  // A table top seen only edge-on: a 2-voxel-thick slab of 0.5 (too thin to be an unknown region)
  // with free space above and below and an occupied rim at x = 2. Texture says free everywhere.
  Grid g(Dims{30, 12, 12}, 0.2f);
  for (int z = 5; z < 7; ++z)
    for (int y = 0; y < 12; ++y) {
      g.at(2, y, z) = 0.9f;
      for (int x = 3; x < 28; ++x) g.at(x, y, z) = 0.5f;
    }
  // A separate ray gap in free space, touching nothing occupied.
  for (int y = 0; y < 12; ++y) g.at(15, y, 10) = 0.5f;
  std::vector<std::uint8_t> st(g.p.size(), 0);
  apply_voxel_rules(st, g, Params());
  for (int y = 0; y < 12; ++y) {
    EXPECT_EQ(st[g.index(3, y, 5)], 1) << "touches the rim";
    EXPECT_EQ(st[g.index(27, y, 6)], 1) << "25 voxels from the rim, same gap";
    EXPECT_EQ(st[g.index(15, y, 10)], 0) << "a gap between rays stays free";
  }
}
