// The final labelling (stages/label.hpp): components, their numbering and the segment table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "isa_levels.hpp"
#include "occseg/error.hpp"
#include "pipeline/segment_internal.hpp"
#include "stages/label.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

TEST(Components, LabelsInScanOrderWithStats) {
  Grid g(Dims{4, 3, 1}, 0.2f);
  // states (y rows):  0 0 2 2
  //                   1 0 0 2
  //                   1 1 0 0
  const std::vector<std::uint8_t> st{0, 0, 2, 2, 1, 0, 0, 2, 1, 1, 0, 0};
  for (std::size_t i = 0; i < st.size(); ++i) g.p[i] = st[i] == 2 ? 0.9f : (st[i] == 1 ? 0.5f : 0.1f);
  LabelArray labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs);
  EXPECT_EQ(labels, (LabelArray{0, 0, 1, 1, 2, 0, 0, 1, 2, 2, 0, 0}));
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
  LabelArray labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs);
  EXPECT_EQ(labels, (LabelArray{0, 1, 0, 0, 1, 0, 0, 0, 0}));
  EXPECT_EQ(segs.size(), 2u);
  EXPECT_EQ(segs[0].voxels, 7u);
}

TEST(Components, DiagonalIsNotConnected) {
  Grid g(Dims{2, 2, 2}, 0.2f);
  const std::vector<std::uint8_t> st{2, 0, 0, 0, 0, 0, 0, 2};
  LabelArray labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs);
  EXPECT_EQ(segs.size(), 3u);
  EXPECT_NE(labels[0], labels[7]);
}

TEST(Components, OccupiedDiagonalsJoinWith26Connectivity) {
  // Two occupied voxels meeting at a corner, two free voxels meeting at a corner.
  Grid g(Dims{2, 2, 2}, 0.2f);
  const std::vector<std::uint8_t> st{2, 1, 1, 0, 1, 0, 1, 2};
  LabelArray labels;
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
    LabelArray labels;
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
      LabelArray labels, labels2;
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

namespace {

// The documented sum of one run's values: voxel k into lane k % 8, the lanes added pairwise.
double lane_sum(const float* v, std::size_t n) {
  double l[8] = {};
  for (std::size_t k = 0; k < n; ++k) l[k % 8] += v[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

void runs_are_summed_in_eight_lanes();

}  // namespace

// A run (a stretch of one segment along x) is summed in eight lanes: with a 1.0 first and
// quarter-ulp values after it, the serial sum stays 1.0 while the lanes keep the small values.
// Runs of every length up to 40 (the vector loop and its tail), then values over many binades;
// every level's kernels.
TEST(Components, RunsAreSummedInEightLanes) {
  EXPECT_GE(for_each_isa([](kernels::Isa) { runs_are_summed_in_eight_lanes(); }), 2);
}

namespace {

void runs_are_summed_in_eight_lanes() {
  for (std::size_t len = 1; len <= 40; ++len) {
    const Dims d{len, 1, 1};
    Grid g(d, std::ldexp(1.0f, -54));
    g.p[0] = 1.0f;
    LabelArray labels;
    std::vector<Segment> segs;
    label_components(std::vector<std::uint8_t>(len, 0), g, labels, segs, 1);
    ASSERT_EQ(segs.size(), 1u);
    EXPECT_EQ(segs[0].mop, lane_sum(g.p.data(), len) / double(len)) << len;
    if (len >= 7) {  // shorter: 1 + 2t at most, which rounds back to 1.0 as well
      double serial = 0;
      for (float v : g.p) serial += v;
      EXPECT_NE(segs[0].mop, serial / double(len)) << len;  // the lanes are not the serial order
    }
  }
  // Three runs per row (free, occupied, free) of lengths that vary by row.
  const Dims d{37, 5, 3};
  Grid g(d, 0.0f);
  std::vector<std::uint8_t> st(d.count(), 0);
  std::uint32_t r = 11;
  for (std::size_t i = 0; i < st.size(); ++i) {
    r = r * 1664525u + 1013904223u;
    g.p[i] = static_cast<float>(std::pow((r >> 8) / double(1u << 24), 6));
    const std::size_t x = i % d.nx, row = i / d.nx;
    st[i] = (x >= 3 + row % 4 && x < 20 + row % 7) ? 2 : 0;
  }
  LabelArray labels;
  std::vector<Segment> segs;
  label_components(st, g, labels, segs, 2);
  std::vector<double> sum(segs.size(), 0.0);
  for (std::size_t i0 = 0; i0 < st.size(); i0 += d.nx)
    for (std::size_t x = 0; x < d.nx;) {
      std::size_t e = x + 1;
      while (e < d.nx && labels[i0 + e] == labels[i0 + x]) ++e;
      sum[labels[i0 + x]] += lane_sum(g.p.data() + i0 + x, e - x);
      x = e;
    }
  ASSERT_EQ(segs.size(), 3u);  // the occupied bar and the free space on either side of it
  for (std::size_t k = 0; k < segs.size(); ++k) EXPECT_EQ(segs[k].mop, sum[k] / double(segs[k].voxels)) << k;
}

}  // namespace

// The run sums are added in scan order within each slab and the slab shares in slab order,
// whichever thread finishes which slab first. Here slab 0 is expensive (random states, many runs)
// and slabs 1..15 are one free region, so with two threads the later slabs finish first. The free
// voxels' values span many binades (u^6 for random u), so the slab shares are rounded sums; the
// values are drawn until adding slab 0's share last would change the sum.
TEST(Components, SlabSharesAreAddedInSlabOrderWhateverFinishesFirst) {
  const Dims d{64, 64, 16 * kLabelSlab};
  Grid g(d, 0.5f);
  std::vector<std::uint8_t> st(d.count(), 0);
  std::uint32_t r = 7;
  auto next = [&] { return r = r * 1664525u + 1013904223u; };
  const std::size_t slab0 = d.nx * d.ny * kLabelSlab;
  for (std::size_t i = 0; i < slab0; ++i) st[i] = static_cast<std::uint8_t>((next() >> 30) % 3);
  LabelArray labels;
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
    for (std::size_t i0 = 0; i0 < st.size(); i0 += d.nx)  // runs of `big` along x
      for (std::size_t x = 0; x < d.nx;) {
        std::size_t e = x + 1;
        while (e < d.nx && labels[i0 + e] == labels[i0 + x]) ++e;
        if (labels[i0 + x] == big) share[i0 / slab0] += lane_sum(g.p.data() + i0 + x, e - x), n += e - x;
        x = e;
      }
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

// Across the first plane of a slab (z = 8), rows are joined run by run. Here the runs of both
// rows end at x = 4, where each row turns to the state the other had: the free and the occupied
// halves touch the other plane's halves only across an edge. Six segments (6-connected), five
// when occupied voxels join across edges (26), the free halves staying apart.
TEST(Components, RunsEndingTogetherAcrossASlabBoundaryJoinOnlyWhatTouches) {
  static_assert(kLabelSlab == 8, "the boundary plane below is z = 8");
  const Dims d{8, 1, 16};
  std::vector<std::uint8_t> st(d.count(), 1);  // unknown above and below
  for (std::size_t x = 0; x < 8; ++x) {
    st[x + 8 * 7] = x < 4 ? 2 : 0;  // z = 7: occupied, then free
    st[x + 8 * 8] = x < 4 ? 0 : 2;  // z = 8: free, then occupied
  }
  const Grid g(d, 0.5f);
  for (bool occ26 : {false, true}) {
    LabelArray labels;
    std::vector<Segment> segs;
    label_components(st, g, labels, segs, 2, occ26);
    const std::uint32_t o = occ26 ? 1 : 4;  // the upper occupied half: its own segment, or the lower's
    const std::uint32_t up = occ26 ? 4 : 5;
    const LabelArray want_z7 = {1, 1, 1, 1, 2, 2, 2, 2}, want_z8 = {3, 3, 3, 3, o, o, o, o};
    EXPECT_EQ(LabelArray(labels.begin() + 56, labels.begin() + 64), want_z7) << occ26;
    EXPECT_EQ(LabelArray(labels.begin() + 64, labels.begin() + 72), want_z8) << occ26;
    EXPECT_EQ(labels[0], 0u);
    EXPECT_EQ(labels.back(), up);
    EXPECT_EQ(segs.size(), occ26 ? 5u : 6u);
  }
}

// A context hands the labelling the run-start bits of its last call: stale bits (all set here)
// and stale labels (all 0) must change nothing, and the storage must be the one handed in.
TEST(Components, ReusedRunStartStorageIsClearedFirst) {
  const Dims d{41, 13, 19};
  Grid g(d, 0.5f);
  std::vector<std::uint8_t> st(d.count());
  std::uint32_t r = 5;
  for (std::size_t i = 0; i < st.size(); ++i) st[i] = static_cast<std::uint8_t>((r = r * 1664525u + 1013904223u) >> 30) % 3;
  LabelArray want;
  std::vector<Segment> want_segs;
  label_components(st, g, want, want_segs, 2, true);
  ASSERT_GT(want_segs.size(), 10u);
  std::vector<std::uint8_t> run_starts(d.count() / 8 + 9, 0xFF);
  const std::uint8_t* storage = run_starts.data();
  LabelArray got(d.count(), 0u);
  std::vector<Segment> got_segs;
  detail::label_components(UninitVector<std::uint8_t>(st.begin(), st.end()), g, got, got_segs, 2, true, run_starts,
                           kernels::active());
  EXPECT_TRUE(std::equal(got.begin(), got.end(), want.begin(), want.end()));
  ASSERT_EQ(got_segs.size(), want_segs.size());
  for (std::size_t k = 0; k < want_segs.size(); ++k) EXPECT_EQ(got_segs[k].voxels, want_segs[k].voxels) << k;
  EXPECT_EQ(run_starts.data(), storage);
}

// A comb: five free teeth (x even) through slabs 0 and 1, joined only by a free bar filling slab 2
// (z >= 16), four occupied columns (x odd, z < 16) between them. Slab 1 holds five local
// components of the free segment, whose root is in slab 0: the statistics take the five as one
// segment of the slab (hand-counted sums; values constant per state, so the means are exact).
TEST(Components, ManyLocalPiecesOfAnEarlierSlabsSegmentAreOneSegment) {
  const Dims d{9, 1, 3 * kLabelSlab};
  Grid g(d, 0.25f);
  std::vector<std::uint8_t> st(d.count(), 0);
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t x = 0; x < d.nx; ++x)
      if (x % 2 == 1 && z < 2 * kLabelSlab) st[x + d.nx * z] = 2, g.p[x + d.nx * z] = 0.75f;
  for (int threads : {1, 2}) {
    LabelArray labels;
    std::vector<Segment> segs;
    label_components(st, g, labels, segs, threads);
    ASSERT_EQ(segs.size(), 5u);  // the free comb, then the columns x = 1, 3, 5, 7
    const Segment& comb = segs[0];
    EXPECT_EQ(comb.state, State::free);
    EXPECT_EQ(comb.voxels, 5u * 16 + 9u * 8);                     // 152
    EXPECT_EQ(comb.mop, 0.25);
    EXPECT_DOUBLE_EQ(comb.centroid[0], 608.0 / 152);            // (0+2+4+6+8)*16 + 36*8
    EXPECT_DOUBLE_EQ(comb.centroid[2], (5.0 * 120 + 9.0 * 156) / 152);  // teeth z 0..15, bar z 16..23
    EXPECT_EQ(comb.bbox_min, (std::array<std::uint32_t, 3>{0, 0, 0}));
    EXPECT_EQ(comb.bbox_max, (std::array<std::uint32_t, 3>{8, 0, 23}));
    for (std::uint32_t k = 1; k < 5; ++k) {
      EXPECT_EQ(segs[k].state, State::occupied);
      EXPECT_EQ(segs[k].voxels, 16u);
      EXPECT_EQ(segs[k].mop, 0.75);
      EXPECT_EQ(segs[k].bbox_min[0], 2 * k - 1);
      EXPECT_DOUBLE_EQ(segs[k].centroid[2], 7.5);
    }
    for (std::size_t z = 0; z < d.nz; ++z)
      for (std::size_t x = 0; x < d.nx; ++x)
        EXPECT_EQ(labels[x + d.nx * z], st[x + d.nx * z] ? (x + 1) / 2 : 0u) << x << " " << z;
  }
}
