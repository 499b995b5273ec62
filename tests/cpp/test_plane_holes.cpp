// Rule 12 (rules/plane_holes.hpp): free runs of at most plane_holes voxels in the inlier band of a
// plane piece seen edge-on, between its own voxels, become occupied. Hand-built maps whose answer
// is known voxel by voxel; the piece is given by hand (rule 11 finds it in the pipeline).
#include <gtest/gtest.h>

#include <cstdint>

#include "occseg/error.hpp"
#include "occseg/params.hpp"
#include "rules/plane_holes.hpp"
#include "stages/label.hpp"
#include "state_scene.hpp"

using namespace occseg;

namespace {

constexpr int F = 0, U = 1, O = 2;

bool in_box(int x, int y, int z, int x0, int y0, int z0, int x1, int y1, int z1) {
  return x >= x0 && x <= x1 && y >= y0 && y <= y1 && z >= z0 && z <= z1;
}

struct Scene : testing_scene::StateScene {
  using StateScene::StateScene;
  void run(const Params& p, const std::vector<PlanePiece>& pieces) {
    label_components(states, grid, labels, segments, 1, true);
    fill_plane_holes(grid, labels, segments, p, pieces);
  }
  State state(int x, int y, int z) const { return segments[at(x, y, z)].state; }
  std::uint64_t count(State s) const {
    std::uint64_t n = 0;
    for (std::size_t i = 0; i < labels.size(); ++i) n += segments[labels[i]].state == s;
    return n;
  }
};

// The horizontal slab z = 5, x and y 5..24 (400 voxels), as rule 11 would report it.
PlanePiece slab_piece(const Grid& g) {
  PlanePiece pc;
  pc.n = {0, 0, 1};
  pc.d = 5;
  pc.u = {1, 0, 0};
  pc.v = {0, 1, 0};
  pc.u0 = 5, pc.u1 = 24, pc.v0 = 5, pc.v1 = 24;
  pc.lo = {5, 5, 5};
  pc.hi = {24, 24, 5};
  pc.voxel = g.index(5, 5, 5);
  return pc;
}

// A slab one voxel thick in free space (seen edge-on: free above and below) with a hole of 3
// voxels (x 10..12, y 10) and a door of 6 x 6 (x 15..20, y 15..20).
int slab_with_holes(int x, int y, int z) {
  if (z != 5 || !in_box(x, y, z, 5, 5, 5, 24, 24, 5)) return F;
  if (y == 10 && x >= 10 && x <= 12) return F;
  if (in_box(x, y, z, 15, 15, 5, 20, 20, 5)) return F;
  return O;
}

Params holes(int gap) {
  Params p;
  p.plane_holes = gap;
  return p;
}

}  // namespace

TEST(PlaneHoles, SmallHoleInAPlaneSeenEdgeOnIsFilledADoorIsKept) {
  Scene s({30, 30, 12}, 0.1, slab_with_holes);
  s.run(holes(4), {slab_piece(s.grid)});
  // The hole's 3 voxels are the slab's now; the door's 36 and everything off the plane stay free.
  for (int x = 10; x <= 12; ++x) EXPECT_EQ(s.at(x, 10, 5), s.at(5, 5, 5)) << x;
  for (int y = 15; y <= 20; ++y)
    for (int x = 15; x <= 20; ++x) EXPECT_EQ(s.state(x, y, 5), State::free) << x << " " << y;
  for (int x = 10; x <= 12; ++x) {
    EXPECT_EQ(s.state(x, 10, 4), State::free);
    EXPECT_EQ(s.state(x, 10, 6), State::free);
  }
  EXPECT_EQ(s.state(4, 10, 5), State::free);  // beside the rim: outside the extent
  EXPECT_EQ(s.count(State::occupied), 400u - 3 - 36 + 3);
  // Statistics: voxel counts, the slab's box and mean occupancy (0.1 for the hole's voxels).
  const Segment& slab = s.segments[s.at(5, 5, 5)];
  EXPECT_EQ(slab.voxels, 364u);
  EXPECT_EQ(slab.bbox_min, (std::array<std::uint32_t, 3>{5, 5, 5}));
  EXPECT_EQ(slab.bbox_max, (std::array<std::uint32_t, 3>{24, 24, 5}));
  EXPECT_NEAR(slab.mop, (361 * 0.9 + 3 * 0.1) / 364, 1e-6);
  const Segment& air = s.segments[s.at(0, 0, 0)];
  EXPECT_EQ(air.voxels, 30u * 30 * 12 - 364);
  EXPECT_EQ(air.state, State::free);
}

TEST(PlaneHoles, GapLongerThanPlaneHolesStaysFree) {
  // The same hole, 3 voxels long along x, but 1 voxel along y: with plane_holes = 2 the runs along
  // x (3) are too long; along y each voxel's run is 1, between the slab's voxels: filled.
  Scene a({30, 30, 12}, 0.1, slab_with_holes);
  a.run(holes(2), {slab_piece(a.grid)});
  EXPECT_EQ(a.state(11, 10, 5), State::occupied);
  // A hole 3 x 3 (x 10..12, y 10..12): runs of 3 both ways; plane_holes = 2 keeps it, 3 fills it.
  const auto square = [](int x, int y, int z) {
    if (z == 5 && in_box(x, y, z, 10, 10, 5, 12, 12, 5)) return F;
    return z == 5 && y == 10 && x >= 10 && x <= 12 ? O : slab_with_holes(x, y, z);
  };
  Scene b({30, 30, 12}, 0.1, square);
  b.run(holes(2), {slab_piece(b.grid)});
  for (int y = 10; y <= 12; ++y)
    for (int x = 10; x <= 12; ++x) EXPECT_EQ(b.state(x, y, 5), State::free) << x << " " << y;
  Scene c({30, 30, 12}, 0.1, square);
  c.run(holes(3), {slab_piece(c.grid)});
  for (int y = 10; y <= 12; ++y)
    for (int x = 10; x <= 12; ++x) EXPECT_EQ(c.state(x, y, 5), State::occupied) << x << " " << y;
  // Off: nothing changes.
  Scene d({30, 30, 12}, 0.1, slab_with_holes);
  d.run(holes(0), {slab_piece(d.grid)});
  EXPECT_EQ(d.state(11, 10, 5), State::free);
}

TEST(PlaneHoles, RunNeedsAnOccupiedEndUnknownAloneIsNotTheSurface) {
  // The rim of a top seen edge-on: the inside unknown (never observed), the rim occupied with
  // free voxels in it. Rim row y = 24: free at x 8..10 between occupied (x 7) and unknown (x 11,
  // a gap of the rim): filled; free at x 16..17 between unknown voxels (x 15 and 18) and free on
  // the outside (y = 25): stays.
  const auto top = [](int x, int y, int z) {
    if (z != 5 || !in_box(x, y, z, 5, 5, 5, 24, 24, 5)) return F;
    if (in_box(x, y, z, 6, 6, 5, 23, 23, 5)) return U;  // the inside
    if (y == 24 && x >= 8 && x <= 10) return F;
    if (y == 24 && (x == 11 || x == 15 || x == 18)) return U;
    if (y == 24 && (x == 16 || x == 17)) return F;
    return O;
  };
  Scene s({30, 30, 12}, 0.1, top);
  s.run(holes(4), {slab_piece(s.grid)});
  for (int x = 8; x <= 10; ++x) EXPECT_EQ(s.state(x, 24, 5), State::occupied) << x;
  EXPECT_EQ(s.state(16, 24, 5), State::free);
  EXPECT_EQ(s.state(17, 24, 5), State::free);
  EXPECT_EQ(s.state(11, 24, 5), State::unknown);  // unknown voxels never change
  EXPECT_EQ(s.state(8, 25, 5), State::free);      // the free space beyond the rim
}

TEST(PlaneHoles, PlaneSeenFromOneSideIsLeftAlone) {
  // A floor: unknown below it (never seen from there), free above: the rays did not run in its
  // plane, and its free voxels are not rays grazing it. The hole stays.
  Scene s({30, 30, 12}, 0.1, [](int x, int y, int z) {
    const int v = slab_with_holes(x, y, z);
    return z < 5 ? U : v;
  });
  s.run(holes(4), {slab_piece(s.grid)});
  EXPECT_EQ(s.state(11, 10, 5), State::free);
}

TEST(PlaneHoles, ParallelLayersOfOneSurfaceAreLeftAlone) {
  // A surface seen face-on under range noise: two parallel layers (z = 5 and 6) of one segment,
  // each a piece; the free voxels in the front layer are the free space in front of the surface.
  Scene s({30, 30, 12}, 0.1, [](int x, int y, int z) {
    if (z == 6 && in_box(x, y, z, 5, 5, 6, 24, 24, 6)) return (x + y) % 3 == 0 ? F : O;
    return slab_with_holes(x, y, z);
  });
  PlanePiece front = slab_piece(s.grid);
  front.d = 6;
  front.lo[2] = front.hi[2] = 6;
  front.voxel = s.grid.index(5, 5, 6);
  s.run(holes(4), {slab_piece(s.grid), front});
  EXPECT_EQ(s.state(11, 10, 5), State::free);
  EXPECT_EQ(s.state(6, 6, 6), State::free);  // (6 + 6) % 3 == 0
}

TEST(PlaneHoles, ParameterIsSetByNameAndOffInThePaperPreset) {
  Params p;
  EXPECT_EQ(get_param(p, "plane_holes"), "4");
  set_param(p, "plane_holes", "2");
  EXPECT_EQ(p.plane_holes, 2);
  EXPECT_EQ(Params::paper().plane_holes, 0);
  EXPECT_THROW(set_param(p, "plane_holes", "17"), Error);
  EXPECT_THROW(set_param(p, "plane_holes", "-1"), Error);
}
