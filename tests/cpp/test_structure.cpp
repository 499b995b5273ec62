// Rule 11 (rules/structure.hpp): several planes per segment are structure, what stands on or
// against them is split off as objects, and coplanar fragments of a surface join it. Hand-built
// maps whose answer is known voxel by voxel.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <set>

#include "occseg/error.hpp"
#include "occseg/params.hpp"
#include "occseg/segment.hpp"
#include "rules/objects.hpp"
#include "rules/structure.hpp"
#include "stages/label.hpp"
#include "state_scene.hpp"

using namespace occseg;

namespace {

constexpr int F = 0, U = 1, O = 2;

struct Scene : testing_scene::StateScene {
  using StateScene::StateScene;
  void run(const Params& p) {
    label_components(states, grid, labels, segments, 1, true);
    split_structure(grid, labels, segments, p);
    assign_kinds(segments, p, grid.dims);
  }
};

bool in_box(int x, int y, int z, int x0, int y0, int z0, int x1, int y1, int z1) {
  return x >= x0 && x <= x1 && y >= y0 && y <= y1 && z >= z0 && z <= z1;
}

// 10 cm voxels: a 3.6 x 3.6 m floor at z = 2 and a 3.6 x 2.6 m wall at x = 2 (unknown below the
// floor and behind the wall, free in the room), a 6 x 6 x 7 box standing on the floor against the
// wall.
int room_with_box(int x, int y, int z) {
  const bool floor = z == 2 && in_box(x, y, z, 2, 2, 2, 37, 37, 2);
  const bool wall = x == 2 && in_box(x, y, z, 2, 2, 2, 2, 37, 27);
  const bool box = in_box(x, y, z, 3, 15, 3, 8, 20, 9);
  if (floor || wall || box) return O;
  if (z < 2 || x < 2) return U;
  return F;
}

// The room of room_with_box() (y <= 39) and beyond it along y free space (unknown under the
// floor's plane and behind the wall's) holding the voxels `beyond` marks occupied.
std::function<int(int, int, int)> room_and_beyond(std::function<bool(int, int, int)> beyond) {
  return [beyond](int x, int y, int z) {
    if (y <= 39) return room_with_box(x, y, z);
    if (beyond(x, y, z)) return O;
    if (z < 2 || x < 2) return U;
    return F;
  };
}

// How many voxels carry label `id`.
std::uint64_t voxels_labelled(const LabelArray& labels, std::uint32_t id) {
  std::uint64_t n = 0;
  for (const std::uint32_t l : labels) n += l == id;
  return n;
}

Params structure_only() {
  Params p;  // the default preset's values
  return p;
}

}  // namespace

TEST(Structure, FloorAndWallAreOneStructureSegmentAndTheBoxAgainstThemAnObject) {
  Scene s({40, 40, 30}, 0.1, room_with_box);
  s.run(structure_only());
  const std::set<std::uint32_t> shell = s.ids([](int x, int y, int z) {
    return (z == 2 && in_box(x, y, z, 2, 2, 2, 37, 37, 2) && !in_box(x, y, z, 3, 15, 2, 8, 20, 2)) ||
           (x == 2 && in_box(x, y, z, 2, 2, 2, 2, 37, 27) && !in_box(x, y, z, 2, 15, 3, 2, 20, 9));
  });
  ASSERT_EQ(shell.size(), 1u);
  const std::uint32_t st = *shell.begin();
  EXPECT_EQ(s.segments[st].kind, Kind::structure);
  // The box is one object, apart from the shell; every voxel of it above the floor's and in front
  // of the wall's inlier layer is in it.
  const std::set<std::uint32_t> box = s.ids([](int x, int y, int z) { return in_box(x, y, z, 4, 15, 4, 8, 20, 9); });
  ASSERT_EQ(box.size(), 1u);
  const std::uint32_t ob = *box.begin();
  EXPECT_NE(ob, st);
  EXPECT_EQ(s.segments[ob].kind, Kind::object);
  EXPECT_EQ(s.segments[ob].state, State::occupied);
  // Nothing else: free space, the unknown, the shell, the box.
  std::size_t occupied = 0;
  for (const Segment& seg : s.segments) occupied += seg.state == State::occupied;
  EXPECT_EQ(occupied, 2u);
  // Statistics recomputed: the two occupied segments hold every occupied voxel.
  std::uint64_t n = 0;
  for (std::uint8_t v : s.states) n += v == O;
  EXPECT_EQ(s.segments[st].voxels + s.segments[ob].voxels, n);
  std::uint64_t in_ob = 0;
  for (std::size_t i = 0; i < s.labels.size(); ++i) in_ob += s.labels[i] == ob;
  EXPECT_EQ(s.segments[ob].voxels, in_ob);
}

TEST(Structure, OffLeavesTheRoomOneSegment) {
  Scene s({40, 40, 30}, 0.1, room_with_box);
  Params p = structure_only();
  p.structure_planes = 0;
  s.run(p);
  EXPECT_EQ(s.at(2, 30, 20), s.at(5, 17, 8));
  EXPECT_EQ(s.at(30, 30, 2), s.at(5, 17, 8));
}

TEST(Structure, PlanesSmallerThanTheExtentAreNotStructure) {
  // The same room at 2 cm voxels is 0.72 m across: furniture, not a building.
  Scene s({40, 40, 30}, 0.02, room_with_box);
  s.run(structure_only());
  EXPECT_EQ(s.at(2, 30, 20), s.at(5, 17, 8));
  EXPECT_NE(s.segments[s.at(2, 30, 20)].kind, Kind::structure);
}

TEST(Structure, WallRingsAreNotTakenForHorizontalPlanes) {
  // A wall scanned in rings: rows of returns every third layer with unknown between them, on a
  // floor. The wall and floor are structure (the proximity rule joined the rings); no ring is split
  // off as an object.
  Scene s({40, 40, 30}, 0.1, [](int x, int y, int z) {
    if (z == 2 && in_box(x, y, z, 2, 2, 2, 37, 37, 2)) return O;
    if (x == 2 && in_box(x, y, z, 2, 2, 2, 2, 37, 27)) return z % 3 == 2 ? O : U;
    if (z < 2 || x < 2) return U;
    return F;
  });
  Params p = structure_only();
  // (The rings are one segment only through rule 6; here they are joined by hand: label, then
  // group_objects.)
  label_components(s.states, s.grid, s.labels, s.segments, 1, true);
  group_objects(s.grid, s.labels, s.segments, p);
  split_structure(s.grid, s.labels, s.segments, p);
  assign_kinds(s.segments, p, s.grid.dims);
  const std::set<std::uint32_t> occ = s.ids([&](int x, int y, int z) { return s.states[s.grid.index(x, y, z)] == O; });
  ASSERT_EQ(occ.size(), 1u);
  EXPECT_EQ(s.segments[*occ.begin()].kind, Kind::structure);
}

namespace {

// 4 cm voxels: a table top (z = 20..21, x 5..44, y 5..24) seen edge-on: its near edge (y = 5) and
// two side edges observed, the interior unknown; its far edge (y = 24) in 2-voxel pieces every 6
// voxels with free voxels between them (as on the simulated table scene); legs under the corners.
int table_edge_on(int x, int y, int z) {
  const bool top = in_box(x, y, z, 5, 5, 20, 44, 24, 21);
  if (top) {
    if (y == 24) return (x % 6 == 0 || x % 6 == 1) && x >= 8 && x <= 40 ? O : F;
    if (y == 5 || x == 5 || x == 44) return O;
    return U;
  }
  for (int lx : {6, 42})
    for (int ly : {6, 22})
      if (in_box(x, y, z, lx, ly, 0, lx + 1, ly + 1, 19)) return O;
  return F;
}

}  // namespace

TEST(Structure, TableTopSeenEdgeOnInPiecesIsOneSegment) {
  Scene s({50, 30, 30}, 0.04, table_edge_on);
  Params p = structure_only();
  p.support_plane = 64;  // a small table: planes of 64 voxels
  s.run(p);
  const std::set<std::uint32_t> table =
      s.ids([&](int x, int y, int z) { return s.states[s.grid.index(x, y, z)] == O && !(y == 24 && z >= 20); });
  ASSERT_EQ(table.size(), 1u);
  const std::set<std::uint32_t> edge =
      s.ids([&](int x, int y, int z) { return s.states[s.grid.index(x, y, z)] == O && y == 24 && z >= 20; });
  EXPECT_EQ(edge, table);
  std::size_t occupied = 0;
  for (const Segment& seg : s.segments) occupied += seg.state == State::occupied;
  EXPECT_EQ(occupied, 1u);
  // Ids stay dense and the table's statistics hold its pieces.
  for (std::size_t i = 0; i < s.segments.size(); ++i) EXPECT_EQ(s.segments[i].id, i);
  std::uint64_t n = 0;
  for (std::uint8_t v : s.states) n += v == O;
  EXPECT_EQ(s.segments[*table.begin()].voxels, n);
}

TEST(Structure, FragmentsOffThePlaneStayApart) {
  // The same pieces two voxels above the top's plane are not part of it.
  Scene s({50, 30, 30}, 0.04, [](int x, int y, int z) {
    if (z >= 23 && z <= 24 && y == 24) return (x % 6 == 0 || x % 6 == 1) && x >= 8 && x <= 40 ? O : F;
    const int v = table_edge_on(x, y, z);
    return y == 24 && z >= 20 && z <= 21 ? F : v;
  });
  Params p = structure_only();
  p.support_plane = 64;
  s.run(p);
  EXPECT_NE(s.at(12, 24, 23), s.at(5, 5, 20));
  EXPECT_NE(s.at(12, 24, 23), s.at(18, 24, 23));
}

TEST(Structure, ParametersByName) {
  Params p;
  EXPECT_EQ(get_param(p, "structure_planes"), "32");
  EXPECT_EQ(get_param(p, "structure_extent"), "2");
  set_param(p, "structure_planes", "8");
  set_param(p, "structure_extent", "1.5");
  EXPECT_EQ(p.structure_planes, 8);
  EXPECT_DOUBLE_EQ(p.structure_extent, 1.5);
  EXPECT_THROW(set_param(p, "structure_planes", "257"), Error);
  EXPECT_THROW(set_param(p, "structure_planes", "-1"), Error);
  EXPECT_THROW(set_param(p, "structure_extent", "0"), Error);
  EXPECT_THROW(set_param(p, "structure_extent", "nan"), Error);
  Params q;
  q.structure_extent = 0;
  EXPECT_THROW(q.validate(), Error);
  EXPECT_EQ(Params::paper().structure_planes, 0);
}

TEST(Structure, ResultsIdenticalForAnyThreadCount) {
  std::vector<LabelArray> labels;
  for (int threads : {1, 2, 3}) {
    Scene s({50, 30, 30}, 0.04, table_edge_on);
    Params p = structure_only();
    p.support_plane = 64;
    p.threads = threads;
    s.run(p);
    labels.push_back(s.labels);
  }
  EXPECT_EQ(labels[0], labels[1]);
  EXPECT_EQ(labels[0], labels[2]);
}

// Four copies of room_with_box, 2 x 2 across, under a tall free volume: four candidates small
// against the map, so their plane searches run side by side (in batches of several) when there are
// threads; each room comes out as the one room does, whatever the thread count.
TEST(Structure, RoomsSearchedSideBySideComeOutAsOneRoomAlone) {
  const auto rooms = [](int x, int y, int z) { return room_with_box(x % 40, y % 40, z); };
  std::vector<LabelArray> labels;
  for (int threads : {1, 2, 3}) {
    Scene s({80, 80, 256}, 0.1, rooms);
    Params p = structure_only();
    p.threads = threads;
    s.run(p);
    labels.push_back(s.labels);
    std::vector<std::uint32_t> boxes;
    for (int ry : {0, 40})
      for (int rx : {0, 40}) {
        const std::set<std::uint32_t> shell = s.ids([&](int x, int y, int z) {
          x -= rx, y -= ry;
          return (z == 2 && in_box(x, y, z, 2, 2, 2, 37, 37, 2) && !in_box(x, y, z, 3, 15, 2, 8, 20, 2)) ||
                 (x == 2 && in_box(x, y, z, 2, 2, 2, 2, 37, 27) && !in_box(x, y, z, 2, 15, 3, 2, 20, 9));
        });
        const std::set<std::uint32_t> box =
            s.ids([&](int x, int y, int z) { return in_box(x - rx, y - ry, z, 4, 15, 4, 8, 20, 9); });
        ASSERT_EQ(shell.size(), 1u) << threads << " threads, room " << rx << "," << ry;
        ASSERT_EQ(box.size(), 1u) << threads << " threads, room " << rx << "," << ry;
        EXPECT_EQ(s.segments[*shell.begin()].kind, Kind::structure);
        EXPECT_EQ(s.segments[*box.begin()].kind, Kind::object);
        boxes.push_back(*box.begin());
      }
    // Objects are numbered in the order of their first voxel (scan order: rooms along x, then y).
    EXPECT_TRUE(std::is_sorted(boxes.begin(), boxes.end()));
    EXPECT_EQ(std::set<std::uint32_t>(boxes.begin(), boxes.end()).size(), 4u);
    std::size_t occupied = 0;
    for (const Segment& seg : s.segments) occupied += seg.state == State::occupied;
    EXPECT_EQ(occupied, 8u);
  }
  EXPECT_EQ(labels[0], labels[1]);
  EXPECT_EQ(labels[0], labels[2]);
}

TEST(Structure, SegmentsLyingInAStructuralPlaneFarFromItsPieceJoinIt) {
  // The room of FloorAndWallAre... and, 2.2 m beyond the end of its wall along y, free space
  // between: a strip of the same wall (x = 2, 16 x 6 voxels: the rings of a far part of a wall),
  // a speckle of two voxels in that plane (y = 50) and a block 5 voxels deep against it. The strip
  // and the speckle lie wholly in the wall's plane, far outside its piece's extent: they join the
  // structure segment. The block has 2 of its 5 layers within a voxel edge of the plane (40 %):
  // it stays apart.
  Scene s({40, 80, 30}, 0.1, room_and_beyond([](int x, int y, int z) {
            return (x == 2 && in_box(x, y, z, 2, 60, 10, 2, 75, 15)) ||
                   (x == 2 && in_box(x, y, z, 2, 50, 12, 2, 51, 12)) || in_box(x, y, z, 2, 60, 20, 6, 65, 25);
          }));
  s.run(structure_only());
  const std::uint32_t shell = s.at(2, 30, 20);
  EXPECT_EQ(s.segments[shell].kind, Kind::structure);
  EXPECT_EQ(s.at(2, 60, 10), shell);
  EXPECT_EQ(s.at(2, 75, 15), shell);
  EXPECT_EQ(s.at(2, 50, 12), shell);  // the speckle
  const std::uint32_t block = s.at(4, 62, 22);
  EXPECT_NE(block, shell);
  EXPECT_EQ(s.at(2, 60, 20), block);
  EXPECT_EQ(s.segments[block].kind, Kind::object);
  // The shell's statistics hold the strip: its voxels are counted in it.
  EXPECT_EQ(s.segments[shell].voxels, voxels_labelled(s.labels, shell));
  for (std::size_t i = 0; i < s.segments.size(); ++i) EXPECT_EQ(s.segments[i].id, i);
}

TEST(Structure, SegmentsLyingInTwoOfItsPlanesAtACornerJoinIt) {
  // The room of FloorAndWallAre... and, 2.2 m beyond the end of its wall along y, free space
  // between: a strip of its corner (y 60-75), the wall's x = 2 for z 2-9 and the floor's z = 2 for
  // x 3-9, 15 voxels a row. 9 of them lie within a voxel edge of the wall's plane and 9 of the
  // floor's (60 % each): in neither plane alone, in the two together. It joins the structure
  // segment. A strip of the same shape at x 20-27 (its "wall" in no plane of the room) stays apart.
  Scene s({40, 80, 30}, 0.1, room_and_beyond([](int x, int y, int z) {
            return y >= 60 && y <= 75 &&
                   ((x == 2 && z >= 2 && z <= 9) || (z == 2 && x >= 3 && x <= 9) || (x == 20 && z >= 2 && z <= 9) ||
                    (z == 2 && x >= 21 && x <= 27));
          }));
  s.run(structure_only());
  const std::uint32_t shell = s.at(2, 30, 20);
  EXPECT_EQ(s.segments[shell].kind, Kind::structure);
  EXPECT_EQ(s.at(2, 60, 9), shell);
  EXPECT_EQ(s.at(9, 75, 2), shell);
  const std::uint32_t other = s.at(20, 60, 9);
  EXPECT_NE(other, shell);
  EXPECT_EQ(s.at(27, 75, 2), other);
  EXPECT_EQ(s.segments[other].kind, Kind::object);
  EXPECT_EQ(s.segments[shell].voxels, voxels_labelled(s.labels, shell));
}

TEST(Structure, SegmentsLyingInAWideUnstructuralPieceOfTheShellJoinIt) {
  // 10 cm voxels: a floor (z = 2) and a wall (x = 2) 5.7 m long up to a ceiling at z = 27 seen
  // in rows along x every 6 voxels (unknown between them: rings too far apart for rule 6) joined
  // at their far end by a row along y; the rows touch the wall, so they are the shell's. Their
  // plane is a piece 3.6 x 5.7 m wide but no area (every row of its 4 x 4 cells has a missing
  // neighbour row), so not structural. A patch of 21 x 8 voxels in that plane beyond the room
  // (y 66-73), touching nothing, lies wholly in it: it joins the shell. Below the ceiling the room
  // is free.
  const auto ceiling_rows = [](int x, int y, int z) {
    if (z == 2 && in_box(x, y, z, 2, 2, 2, 37, 58, 2)) return O;
    if (x == 2 && in_box(x, y, z, 2, 2, 2, 2, 58, 27)) return O;
    if (z == 27 && in_box(x, y, z, 2, 2, 27, 37, 58, 27) && ((y - 2) % 6 == 0 || x == 37)) return O;
    if (z == 27 && in_box(x, y, z, 10, 66, 27, 30, 73, 27)) return O;
    if (z < 2 || x < 2 || z >= 27) return U;
    return F;
  };
  Scene s({40, 80, 30}, 0.1, ceiling_rows);
  s.run(structure_only());
  const std::uint32_t shell = s.at(2, 30, 20);
  EXPECT_EQ(s.segments[shell].kind, Kind::structure);
  EXPECT_EQ(s.at(30, 14, 27), shell);  // a ceiling row
  EXPECT_EQ(s.at(20, 70, 27), shell);  // the patch
  std::size_t occupied = 0;
  for (const Segment& seg : s.segments) occupied += seg.state == State::occupied;
  EXPECT_EQ(occupied, 1u);
}
