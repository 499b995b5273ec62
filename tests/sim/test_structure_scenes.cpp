// Rule 11 (structure and objects) on the simulated table scene at its full size (320 x 320 x 128,
// 4 cm, seed 1): the top, seen only edge-on by the planar scans, lies in pieces with free voxels
// between them (9 occupied segments on the table without the rule, 8 of them clutter); the pieces
// lie in the plane of the top and join it.
#include <gtest/gtest.h>

#include "occseg/segment.hpp"
#include "occseg/sim/metrics.hpp"

using namespace occseg;
using namespace occseg::sim;

TEST(SimStructure, TableTopSeenEdgeOnIsOneSegment) {
  const Scene scene = make_scene("table");
  const ScanConfig config;  // seed 1
  const Grid map = simulate_map(scene, config);
  const Truth truth = ground_truth(scene, config);
  const Result r = segment(map, Params::defaults());
  std::vector<State> states;
  for (const Segment& s : r.segments) states.push_back(s.state);
  const Scores s = score_segmentation(truth, r.labels, states);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].segments, 1u) << "the table is one occupied segment, its top's pieces included";
  EXPECT_EQ(s.spanning_segments, 0u);
  EXPECT_LE(s.segments, 100u);
}
