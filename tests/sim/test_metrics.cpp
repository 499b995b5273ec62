#include <gtest/gtest.h>

#include "occseg/error.hpp"
#include "occseg/sim/baseline.hpp"
#include "occseg/sim/metrics.hpp"

using namespace occseg;
using namespace occseg::sim;

namespace {
constexpr std::uint8_t F = 0, U = 1, O = 2;
const State SF = State::free, SU = State::unknown, SO = State::occupied;

Truth line(std::vector<std::uint8_t> state, std::vector<std::uint16_t> objects) {
  Truth t;
  t.dims = Dims{state.size(), 1, 1};
  t.state = std::move(state);
  t.objects = std::move(objects);
  return t;
}
}  // namespace

TEST(SimMetrics, HandComputedScores) {
  const Truth t = line({F, F, O, U, U, F}, {0, 0, 1, 1, 0, 0});
  // Labelled states F F O F U F in five segments.
  const Scores s = score_segmentation(t, {0, 0, 1, 2, 3, 4}, {SF, SO, SF, SU, SF}, 1);
  EXPECT_DOUBLE_EQ(s.accuracy, 5.0 / 6.0);
  EXPECT_DOUBLE_EQ(s.iou[0], 3.0 / 4.0);  // truth {0,1,5}, labelled {0,1,3,5}
  EXPECT_DOUBLE_EQ(s.iou[1], 1.0 / 2.0);  // truth {3,4}, labelled {4}
  EXPECT_DOUBLE_EQ(s.iou[2], 1.0);
  EXPECT_EQ(s.object_voxels, 2u);
  EXPECT_EQ(s.object_free, 1u);           // voxel 3
  EXPECT_DOUBLE_EQ(s.object_free_share, 0.5);
  EXPECT_EQ(s.unknown_voxels, 2u);
  EXPECT_DOUBLE_EQ(s.unknown_free_share, 0.5);
  EXPECT_EQ(s.segments, 5u);
  EXPECT_EQ(s.segments_by_state[0], 3u);
  EXPECT_EQ(s.segments_by_state[2], 1u);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].voxels, 2u);
  EXPECT_EQ(s.objects[0].labelled_free, 1u);
  EXPECT_EQ(s.objects[0].surface, 1u);
  EXPECT_EQ(s.objects[0].surface_found, 1u);
  EXPECT_EQ(s.objects[0].segments, 1u);
  EXPECT_DOUBLE_EQ(s.objects[0].largest_share, 1.0);
  EXPECT_EQ(s.spanning_segments, 0u);
  EXPECT_EQ(s.stray_segments, 0u);
}

TEST(SimMetrics, SpanningAndStraySegments) {
  const Truth t = line({O, F, F, F, F, F, O}, {1, 0, 0, 0, 0, 0, 2});
  const Scores merged = score_segmentation(t, {0, 0, 0, 0, 0, 0, 0}, {SO}, 1);
  EXPECT_EQ(merged.spanning_segments, 1u);
  EXPECT_EQ(merged.objects[0].segments, 1u);
  EXPECT_EQ(merged.objects[1].segments, 1u);
  EXPECT_DOUBLE_EQ(merged.accuracy, 2.0 / 7.0);
  // Occupied 0 | free 1-2 | occupied 3 (far from both) | free 4-5 | occupied 6.
  const Scores split = score_segmentation(t, {0, 1, 1, 2, 3, 3, 4}, {SO, SF, SO, SF, SO}, 1);
  EXPECT_EQ(split.spanning_segments, 0u);
  EXPECT_EQ(split.stray_segments, 1u);
  EXPECT_EQ(split.objects[0].segments, 1u);
  EXPECT_EQ(split.objects[1].segments, 1u);
  // Object 1 as two occupied segments of 1 and 2 voxels (reach 2): largest share 2/3.
  const Truth t2 = line({O, O, F, F, F}, {1, 1, 0, 0, 0});
  const Scores two = score_segmentation(t2, {0, 1, 2, 3, 3}, {SO, SF, SO, SF}, 2);
  EXPECT_EQ(two.objects[0].segments, 2u);
  const Scores two_b = score_segmentation(t2, {0, 0, 1, 2, 3}, {SO, SF, SO, SF}, 3);
  EXPECT_DOUBLE_EQ(two_b.objects[0].largest_share, 2.0 / 3.0);
}

TEST(SimMetrics, AttributionGoesToTheNearestObjectWithinReach) {
  const auto a = attribute_to_objects(Dims{7, 1, 1}, {1, 0, 0, 0, 0, 0, 2}, 2);
  EXPECT_EQ(a, (std::vector<std::uint16_t>{1, 1, 1, 0, 2, 2, 2}));
  const auto tie = attribute_to_objects(Dims{5, 1, 1}, {1, 0, 0, 0, 2}, 2);
  EXPECT_EQ(tie, (std::vector<std::uint16_t>{1, 1, 1, 2, 2})) << "ties go to the first in voxel order";
  const auto z = attribute_to_objects(Dims{1, 1, 4}, {0, 0, 0, 3}, 1);
  EXPECT_EQ(z, (std::vector<std::uint16_t>{0, 0, 3, 3}));
}

TEST(SimMetrics, BadInputNamesTheProblem) {
  const Truth t = line({F, F}, {0, 0});
  EXPECT_THROW(score_segmentation(t, {0}, {SF}), Error);
  try {
    score_segmentation(t, {0, 5}, {SF});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::out_of_range);
    EXPECT_NE(std::string(e.what()).find("(1, 0, 0)"), std::string::npos) << e.what();
  }
}

TEST(SimBaseline, ThresholdsEachVoxelThenLabelsComponents) {
  Grid g(Dims{5, 1, 1});
  g.p = {0.1f, 0.5f, 0.9f, 0.9f, 0.499f};
  const Result r = threshold_segmentation(g, Params::paper());
  EXPECT_EQ(r.labels, (LabelArray{0, 1, 2, 2, 3}));
  ASSERT_EQ(r.segments.size(), 4u);
  EXPECT_EQ(r.segments[1].state, State::unknown);
  EXPECT_EQ(r.segments[2].voxels, 2u);
  EXPECT_EQ(r.segments[3].state, State::unknown) << "0.499 lies in the unknown band [0.498, 0.502]";
  g.p[0] = 1.5f;
  EXPECT_THROW(threshold_segmentation(g), Error);
}
