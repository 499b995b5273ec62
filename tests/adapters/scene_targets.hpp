// Issue 23's targets for the scene table of a real file (docs/experiments.md, "All rules
// together"), counted as scripts/scene-report.py counts them: at most 150 structure and object
// segments covering at least 95 % of the occupied voxels, clutter at most 5 % of them, at most 10
// free or unknown segments of at most 8 voxels, and no voxel whose own probability is occupied
// labelled free.
#pragma once
#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"

namespace occseg_test {

using namespace occseg;

struct SceneTable {
  std::size_t structure_and_objects = 0, small_free_or_unknown = 0, occupied_labelled_free = 0;
  std::size_t occupied_voxels = 0, covered_voxels = 0, clutter_voxels = 0;
};

inline SceneTable scene_table(const Grid& g, const Result& r, const Params& p) {
  SceneTable t;
  for (const Segment& s : r.segments) {
    if (s.state != State::occupied) {
      t.small_free_or_unknown += s.voxels <= 8;
      continue;
    }
    t.occupied_voxels += s.voxels;
    if (s.kind == Kind::structure || s.kind == Kind::object) ++t.structure_and_objects, t.covered_voxels += s.voxels;
    if (s.kind == Kind::clutter) t.clutter_voxels += s.voxels;
  }
  for (std::size_t i = 0; i < g.p.size(); ++i)
    t.occupied_labelled_free += p.state_of(g.p[i]) == State::occupied && r.segments[r.labels[i]].state == State::free;
  return t;
}

inline void expect_scene_targets(const SceneTable& t, const std::string& what) {
  EXPECT_GT(t.occupied_voxels, 0u) << what;
  EXPECT_LE(t.structure_and_objects, 150u) << what;
  EXPECT_GE(double(t.covered_voxels), 0.95 * double(t.occupied_voxels)) << what << ": structure and objects cover";
  EXPECT_LE(double(t.clutter_voxels), 0.05 * double(t.occupied_voxels)) << what << ": clutter";
  EXPECT_LE(t.small_free_or_unknown, 10u) << what << ": free or unknown segments of <= 8 voxels";
  EXPECT_EQ(t.occupied_labelled_free, 0u) << what << ": voxels occupied by their own probability labelled free";
}

}  // namespace occseg_test
