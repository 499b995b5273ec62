// Rule 11 (structure and objects) on the real OctoMap corridor ../shared/data/geb079.bt (8 cm):
// its two long corridor walls and its floor are structure, not objects, and the scene table stays
// within issue 23's bounds.
#include <gtest/gtest.h>

#include <string>

#include "occseg/octomap_file.hpp"
#include "occseg/segment.hpp"
#include "scene_targets.hpp"

using namespace occseg;

namespace {

const std::string kBt = std::string(OCCSEG_SHARED_DATA) + "/geb079.bt";

// The share of the occupied voxels in the box [x0, x1) x [y0, y1) x [z0, z1) whose segment has kind k.
double share(const Grid& g, const Result& r, Kind k, int x0, int x1, int y0, int y1, int z0, int z1,
             std::size_t& occupied) {
  std::size_t hit = 0;
  occupied = 0;
  for (int z = z0; z < z1; ++z)
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const Segment& s = r.segments[r.labels[g.index(std::size_t(x), std::size_t(y), std::size_t(z))]];
        if (s.state != State::occupied) continue;
        ++occupied;
        hit += s.kind == k;
      }
  return occupied ? double(hit) / double(occupied) : 0.0;
}

}  // namespace

TEST(StructureRealData, CorridorWallsAndFloorOfGeb079AreStructure) {
  const Grid g = read_octree_file(kBt);
  ASSERT_EQ(g.dims.nx, 487u);
  ASSERT_EQ(g.dims.ny, 187u);
  ASSERT_EQ(g.dims.nz, 39u);
  const Result r = segment(g, Params::defaults());
  std::size_t n = 0;
  // The corridor's walls (y 74-79 and 106-111 voxels, x 100-399, 0.1-2.3 m above the floor) and
  // its floor (z 1-4 between them).
  EXPECT_GE(share(g, r, Kind::structure, 100, 400, 74, 80, 5, 34, n), 0.9);
  EXPECT_GT(n, 10000u);
  EXPECT_GE(share(g, r, Kind::structure, 100, 400, 106, 112, 5, 34, n), 0.9);
  EXPECT_GT(n, 10000u);
  EXPECT_GE(share(g, r, Kind::structure, 100, 400, 82, 104, 1, 5, n), 0.9);
  EXPECT_GT(n, 1000u);
  // Issue 23's bounds on the scene table.
  occseg_test::expect_scene_targets(occseg_test::scene_table(g, r, Params::defaults()), "geb079.bt");
  std::size_t objects = 0;
  for (const Segment& s : r.segments) objects += s.kind == Kind::object;
  EXPECT_GE(objects, 10u) << "the furniture is split off the shell";
}
