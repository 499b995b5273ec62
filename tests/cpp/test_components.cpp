#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "occseg/components.hpp"
#include "occseg/error.hpp"
#include "segment_internal.hpp"

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

// Random three-state maps with runs of 1..20 voxels (the statistics pass finds runs by label,
// 4 at a time), sizes not multiples of the slab or vector widths, 6- and 26-connectivity, 1 and
// 3 threads: every segment's table entry equals what its labelled voxels give, and the overload
// that takes the states over gives the same labels and table and leaves the states empty.
TEST(Components, StatisticsMatchTheLabelledVoxelsAndTakingStatesOverChangesNothing) {
  const Dims d{37, 23, 19};
  Grid g(d, 0.5f);
  std::vector<std::uint8_t> st(d.count());
  std::uint32_t r = 99;
  auto rnd = [&] { return r = r * 1664525u + 1013904223u, r >> 8; };
  for (std::size_t i = 0; i < st.size();) {
    const std::size_t run = 1 + rnd() % 20;
    const auto v = static_cast<std::uint8_t>(rnd() % 3);
    for (std::size_t k = 0; k < run && i < st.size(); ++k, ++i) st[i] = v;
  }
  for (std::size_t i = 0; i < st.size(); ++i) g.p[i] = 0.05f + 0.3f * st[i] + 0.001f * float(i % 7);
  for (bool occ26 : {false, true})
    for (int threads : {1, 3}) {
      std::vector<std::uint32_t> labels, labels2;
      std::vector<Segment> segs, segs2;
      label_components(st, g, labels, segs, threads, occ26);
      std::vector<std::uint8_t> copy = st;
      label_components(std::move(copy), g, labels2, segs2, threads, occ26);
      EXPECT_TRUE(copy.empty());
      ASSERT_EQ(labels, labels2);
      ASSERT_EQ(segs.size(), segs2.size());
      ASSERT_GT(segs.size(), 100u);
      std::vector<std::uint64_t> n(segs.size(), 0);
      std::vector<std::array<double, 3>> sum(segs.size(), {0, 0, 0});
      std::vector<std::array<std::uint32_t, 3>> lo(segs.size(), {~0u, ~0u, ~0u}), hi(segs.size(), {0, 0, 0});
      std::vector<double> mop(segs.size(), 0.0);
      for (std::size_t i = 0; i < st.size(); ++i) {
        const std::uint32_t l = labels[i];
        ASSERT_LT(l, segs.size());
        ASSERT_EQ(static_cast<std::uint8_t>(segs[l].state), st[i]) << "voxel " << i;
        const std::uint32_t c[3] = {static_cast<std::uint32_t>(i % d.nx), static_cast<std::uint32_t>(i / d.nx % d.ny),
                                    static_cast<std::uint32_t>(i / (d.nx * d.ny))};
        ++n[l];
        mop[l] += g.p[i];
        for (int a = 0; a < 3; ++a) {
          sum[l][a] += c[a];
          lo[l][a] = std::min(lo[l][a], c[a]);
          hi[l][a] = std::max(hi[l][a], c[a]);
        }
      }
      for (std::size_t k = 0; k < segs.size(); ++k) {
        const Segment &a = segs[k], &b = segs2[k];
        EXPECT_EQ(a.id, k);
        EXPECT_EQ(a.voxels, n[k]) << k;
        EXPECT_EQ(a.bbox_min, lo[k]) << k;
        EXPECT_EQ(a.bbox_max, hi[k]) << k;
        for (int ax = 0; ax < 3; ++ax) EXPECT_DOUBLE_EQ(a.centroid[ax], sum[k][ax] / double(n[k])) << k;
        EXPECT_NEAR(a.mop, mop[k] / double(n[k]), 1e-12) << k;
        EXPECT_EQ(a.state, b.state);
        EXPECT_EQ(a.voxels, b.voxels);
        EXPECT_EQ(a.mop, b.mop);
        EXPECT_EQ(a.bbox_min, b.bbox_min);
        EXPECT_EQ(a.bbox_max, b.bbox_max);
        EXPECT_EQ(a.centroid, b.centroid);
      }
    }
}

// The mean occupancy is summed per slab in scan order and the slab shares are added in slab
// order, whichever thread finishes which slab first. Here slab 0 is expensive (random states,
// many runs) and slabs 1..15 are one free region, so with two threads the later slabs finish
// first. The free voxels' values span many binades (u^6 for random u), so the slab shares are
// rounded sums; the values are drawn until adding slab 0's share last would change the sum.
TEST(Components, SlabSharesAreAddedInSlabOrderWhateverFinishesFirst) {
  const Dims d{64, 64, 16 * kLabelSlab};
  Grid g(d, 0.5f);
  std::vector<std::uint8_t> st(d.count(), 0);
  std::uint32_t r = 7;
  auto next = [&] { return r = r * 1664525u + 1013904223u; };
  const std::size_t slab0 = d.nx * d.ny * kLabelSlab;
  for (std::size_t i = 0; i < slab0; ++i) st[i] = static_cast<std::uint8_t>((next() >> 30) % 3);
  std::vector<std::uint32_t> labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs, 1, true);  // membership only: it does not depend on p
  const std::uint32_t big = labels.back();         // the free region of slabs 1..15
  double forward = 0;
  std::uint64_t n = 0;
  for (int draw = 0;; ++draw) {
    ASSERT_LT(draw, 50) << "no order-sensitive values found";
    for (std::size_t i = 0; i < st.size(); ++i)
      g.p[i] = st[i] == 0 ? static_cast<float>(0.4 * std::pow((next() >> 8) / double(1u << 24), 6))
                          : (st[i] == 1 ? 0.5f : 0.9f);
    double share[16] = {};
    n = 0;
    for (std::size_t i = 0; i < st.size(); ++i)
      if (labels[i] == big) share[i / slab0] += g.p[i], ++n;
    double zero_last = 0;
    forward = 0;
    for (int s = 0; s < 16; ++s) forward += share[s];
    for (int s = 1; s < 16; ++s) zero_last += share[s];
    zero_last += share[0];
    if (forward != zero_last && share[0] > 0) break;
  }
  for (int run = 0; run < 3; ++run) {
    label_components(st, g, labels, segs, 2, true);
    EXPECT_EQ(segs[big].mop, forward / double(n)) << "run " << run;
  }
}

TEST(Components, LabelRangeIsCheckedBeforeAnythingIsAllocated) {
  // segment() asks before its first allocation (a map that large would first fill 4 bytes per
  // voxel of scratch); labels are uint32 with one value to spare.
  EXPECT_NO_THROW(detail::check_labels_fit((std::size_t(1) << 32) - 2));
  try {
    detail::check_labels_fit((std::size_t(1) << 32) - 1);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::unsupported);
    EXPECT_NE(std::string(e.what()).find("4294967295 voxels"), std::string::npos) << e.what();
  }
}
