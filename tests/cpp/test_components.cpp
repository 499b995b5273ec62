#include <gtest/gtest.h>

#include "occseg/components.hpp"

using namespace occseg;

TEST(Components, LabelsInScanOrderWithStats) {
  Grid g(Dims{4, 3, 1}, 0.2f);
  // states (y rows):  0 0 2 2
  //                   1 0 0 2
  //                   1 1 0 0
  const std::vector<std::uint8_t> st{0, 0, 2, 2, 1, 0, 0, 2, 1, 1, 0, 0};
  for (std::size_t i = 0; i < st.size(); ++i) g.p[i] = st[i] == 2 ? 0.9f : (st[i] == 1 ? 0.5f : 0.1f);
  std::vector<std::uint32_t> labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs);
  EXPECT_EQ(labels, (std::vector<std::uint32_t>{0, 0, 1, 1, 2, 0, 0, 1, 2, 2, 0, 0}));
  ASSERT_EQ(segs.size(), 3u);
  EXPECT_EQ(segs[0].state, State::free);
  EXPECT_EQ(segs[0].voxels, 6u);
  EXPECT_EQ(segs[1].state, State::occupied);
  EXPECT_EQ(segs[1].voxels, 3u);
  EXPECT_NEAR(segs[1].mop, 0.9, 1e-6);
  EXPECT_EQ(segs[1].bbox_min, (std::array<std::uint32_t, 3>{2, 0, 0}));
  EXPECT_EQ(segs[1].bbox_max, (std::array<std::uint32_t, 3>{3, 1, 0}));
  EXPECT_NEAR(segs[1].centroid[0], (2 + 3 + 3) / 3.0, 1e-12);
  EXPECT_NEAR(segs[1].centroid[1], 1 / 3.0, 1e-12);
  EXPECT_EQ(segs[2].bbox_min, (std::array<std::uint32_t, 3>{0, 1, 0}));
}

TEST(Components, UShapeMergesLate) {
  // A U of state 2 whose arms meet only at the bottom row: one component, id by first voxel.
  Grid g(Dims{3, 3, 1}, 0.2f);
  const std::vector<std::uint8_t> st{2, 0, 2, 2, 0, 2, 2, 2, 2};
  std::vector<std::uint32_t> labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs);
  EXPECT_EQ(labels, (std::vector<std::uint32_t>{0, 1, 0, 0, 1, 0, 0, 0, 0}));
  EXPECT_EQ(segs.size(), 2u);
  EXPECT_EQ(segs[0].voxels, 7u);
}

TEST(Components, DiagonalIsNotConnected) {
  Grid g(Dims{2, 2, 2}, 0.2f);
  const std::vector<std::uint8_t> st{2, 0, 0, 0, 0, 0, 0, 2};
  std::vector<std::uint32_t> labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs);
  EXPECT_EQ(segs.size(), 3u);
  EXPECT_NE(labels[0], labels[7]);
}

TEST(Components, OccupiedDiagonalsJoinWith26Connectivity) {
  // Two occupied voxels meeting at a corner, two free voxels meeting at a corner.
  Grid g(Dims{2, 2, 2}, 0.2f);
  const std::vector<std::uint8_t> st{2, 1, 1, 0, 1, 0, 1, 2};
  std::vector<std::uint32_t> labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs, 1, true);
  EXPECT_EQ(labels[0], labels[7]) << "occupied: corner contact joins";
  EXPECT_NE(labels[3], labels[5]) << "free: only faces join";
  EXPECT_EQ(segs[labels[0]].voxels, 2u);
  EXPECT_EQ(segs[labels[0]].bbox_max, (std::array<std::uint32_t, 3>{1, 1, 1}));
}

TEST(Components, SlopedShellAcrossSlabsIsOneSegment) {
  // A one-voxel staircase x = y = z crossing several 8-plane labelling slabs: 26 joins it, 6 not.
  Grid g(Dims{20, 20, 20}, 0.2f);
  std::vector<std::uint8_t> st(g.p.size(), 0);
  for (std::size_t k = 0; k < 20; ++k) st[g.index(k, k, k)] = 2;
  for (int threads : {1, 3}) {
    std::vector<std::uint32_t> labels;
    std::vector<Segment> segs;
    label_components(st, g, labels, segs, threads, true);
    EXPECT_EQ(segs.size(), 2u);
    EXPECT_EQ(segs[labels[g.index(19, 19, 19)]].voxels, 20u);
    label_components(st, g, labels, segs, threads, false);
    EXPECT_EQ(segs.size(), 21u);
  }
}
