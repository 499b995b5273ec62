// segments.ot (occseg/octomap_segments.hpp): written, then read back with liboctomap. One leaf
// per occupied voxel at depth 16, coloured as its segment, resolution and positions exact.
#include <gtest/gtest.h>

#include <octomap/AbstractOcTree.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>

#include "occseg/error.hpp"
#include "occseg/octomap_file.hpp"
#include "occseg/octomap_segments.hpp"
#include "occseg/octomap_tree.hpp"
#include "occseg/segment.hpp"
#include "occseg/segment_colour.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {

std::string tmp(const std::string& name) {
  fs::create_directories(OCCSEG_TEST_TMP);
  return std::string(OCCSEG_TEST_TMP) + "/" + name;
}

std::unique_ptr<octomap::ColorOcTree> read_back(const std::string& path) {
  std::unique_ptr<octomap::AbstractOcTree> t(octomap::AbstractOcTree::read(path));
  EXPECT_TRUE(t) << path;
  auto* c = dynamic_cast<octomap::ColorOcTree*>(t.get());
  EXPECT_TRUE(c) << "not a ColorOcTree: " << (t ? t->getTreeType() : "nothing");
  if (!c) return nullptr;
  t.release();
  return std::unique_ptr<octomap::ColorOcTree>(c);
}

// Two boxes in free space, 0.1 m voxels, the origin on OctoMap's lattice (a whole number of
// voxels from the world origin, negative on x).
Grid two_boxes(std::array<double, 3> origin) {
  Grid g(Dims{20, 16, 12}, 0.12f, 0.1);
  g.origin = origin;
  for (std::size_t z = 0; z < 12; ++z)
    for (std::size_t y = 0; y < 16; ++y)
      for (std::size_t x = 0; x < 20; ++x) {
        const bool a = x >= 2 && x < 6 && y >= 3 && y < 7 && z >= 1 && z < 5;
        const bool b = x >= 10 && x < 17 && y >= 8 && y < 13 && z >= 4 && z < 10;
        if (a || b) g.at(x, y, z) = 0.97f;
      }
  return g;
}

// Checks that the tree read back holds exactly the occupied voxels of `r`: one leaf each at
// depth 16, at the voxel's centre moved by `shift`, with its segment's colour.
void expect_tree_is_segmentation(const octomap::ColorOcTree& tree, const Grid& g, const Result& r,
                                 std::array<double, 3> shift) {
  EXPECT_EQ(tree.getResolution(), g.voxel_size);
  std::map<std::array<long, 3>, std::uint32_t> want;  // expected leaf key -> segment
  std::size_t i = 0;
  for (std::size_t z = 0; z < g.dims.nz; ++z)
    for (std::size_t y = 0; y < g.dims.ny; ++y)
      for (std::size_t x = 0; x < g.dims.nx; ++x, ++i)
        if (r.segments[r.labels[i]].state == State::occupied) {
          const double c[3] = {g.origin[0] + shift[0] + (double(x) + 0.5) * g.voxel_size,
                               g.origin[1] + shift[1] + (double(y) + 0.5) * g.voxel_size,
                               g.origin[2] + shift[2] + (double(z) + 0.5) * g.voxel_size};
          const octomap::OcTreeKey k = tree.coordToKey(c[0], c[1], c[2]);
          want[{long(k[0]), long(k[1]), long(k[2])}] = r.labels[i];
          // The voxel's centre is the key's centre (to rounding), not just inside its cell.
          for (int a = 0; a < 3; ++a) EXPECT_NEAR(tree.keyToCoord(k[a]), c[a], 1e-9 * g.voxel_size);
        }
  ASSERT_FALSE(want.empty());
  std::size_t leaves = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it, ++leaves) {
    EXPECT_EQ(it.getDepth(), 16u);
    const octomap::OcTreeKey k = it.getKey();
    const auto w = want.find({long(k[0]), long(k[1]), long(k[2])});
    ASSERT_NE(w, want.end()) << "a leaf where no occupied voxel is: " << it.getCoordinate();
    EXPECT_TRUE(tree.isNodeOccupied(*it));
    const Rgb c = segment_colour(w->second);
    const octomap::ColorOcTreeNode::Color got = it->getColor();
    EXPECT_EQ(got, octomap::ColorOcTreeNode::Color(c.r, c.g, c.b)) << "segment " << w->second;
  }
  EXPECT_EQ(leaves, want.size());
}

}  // namespace

TEST(SegmentsOctree, OneColouredLeafPerOccupiedVoxel) {
  const Grid g = two_boxes({-0.8, 0.3, 1.2});
  const Result r = segment(g, Params::defaults());
  std::size_t objects = 0;
  for (const Segment& s : r.segments) objects += s.state == State::occupied;
  ASSERT_EQ(objects, 2u);
  ASSERT_NE(segment_colour(r.labels[g.index(2, 3, 1)]).r, segment_colour(r.labels[g.index(10, 8, 4)]).r)
      << "the test wants two segments of different colours";
  const std::string path = tmp("two_boxes.ot");
  const OctreePlacement place = write_segments_octree(path, g, r);
  EXPECT_FALSE(place.snapped);
  const auto tree = read_back(path);
  ASSERT_TRUE(tree);
  expect_tree_is_segmentation(*tree, g, r, {0, 0, 0});
  EXPECT_EQ(tree->getNumLeafNodes(), std::size_t(4 * 4 * 4 + 7 * 5 * 6));
}

// Eight voxels of one octant, two segments of equal probability: OctoMap's ColorOcTree would
// prune them into one leaf of a mixed colour; the writer keeps all eight.
TEST(SegmentsOctree, NeighboursOfDifferentSegmentsAreNotMerged) {
  Grid g(Dims{4, 4, 4}, 0.97f, 0.25);
  Result r;
  r.dims = g.dims;
  r.labels.assign(g.dims.count(), 0);
  r.segments.resize(3);
  r.segments[0].state = State::free;
  for (std::uint32_t s = 1; s < 3; ++s) {
    r.segments[s].id = s;
    r.segments[s].state = State::occupied;
  }
  for (std::size_t z = 0; z < 2; ++z)
    for (std::size_t y = 0; y < 2; ++y)
      for (std::size_t x = 0; x < 2; ++x) r.labels[g.index(x, y, z)] = x == 0 ? 1 : 2;
  ASSERT_NE(segment_colour(1).r, segment_colour(2).r);
  const std::string path = tmp("octant.ot");
  write_segments_octree(path, g, r);
  const auto tree = read_back(path);
  ASSERT_TRUE(tree);
  expect_tree_is_segmentation(*tree, g, r, {0, 0, 0});
  EXPECT_EQ(tree->getNumLeafNodes(), 8u);
}

// An origin between lattice points: the whole map moves by less than half a voxel, and says so.
TEST(SegmentsOctree, OriginOffTheLatticeIsSnappedToTheNearestLatticePoint) {
  const Grid g = two_boxes({0.03, -0.26, 0.5});  // 0.3, -2.6 and 5 voxels
  const Result r = segment(g, Params::defaults());
  const std::string path = tmp("snapped.ot");
  const OctreePlacement place = write_segments_octree(path, g, r);
  EXPECT_TRUE(place.snapped);
  EXPECT_NEAR(place.shift[0], -0.03, 1e-12);
  EXPECT_NEAR(place.shift[1], -0.04, 1e-12);
  EXPECT_NEAR(place.shift[2], 0.0, 1e-12);
  const auto tree = read_back(path);
  ASSERT_TRUE(tree);
  expect_tree_is_segmentation(*tree, g, r, place.shift);
}

TEST(SegmentsOctree, MapBeyondOctomapKeysIsBadValue) {
  Grid g = two_boxes({5000.0, 0, 0});  // 50000 voxels of 0.1 m from the origin: keys end at 32767
  const Result r = segment(g, Params::defaults());
  const std::string path = tmp("far.ot");
  try {
    write_segments_octree(path, g, r);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::bad_value);
    EXPECT_NE(std::string(e.what()).find("2^16 keys of OctoMap"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
}

// The OctoMap corridor (../shared/data/geb079.bt, 8 cm): segments.ot at the tree's own resolution
// puts every occupied voxel on the key of the source tree's leaf it came from.
TEST(SegmentsOctree, RealCorridorLandsOnTheSourceTreesKeys) {
  const std::string bt = std::string(OCCSEG_SHARED_DATA) + "/geb079.bt";
  if (!fs::exists(bt)) GTEST_SKIP() << "no " << bt;
  OctreeOptions o;
  o.bbox = Box{{-4.0, -3.52, -0.32}, {4.0, 3.44, 2.8}};
  const Grid g = read_octree_file(bt, o);
  const Result r = segment(g, Params::defaults());
  const std::string path = tmp("corridor.ot");
  const OctreePlacement place = write_segments_octree(path, g, r);
  EXPECT_FALSE(place.snapped);
  const auto tree = read_back(path);
  ASSERT_TRUE(tree);
  expect_tree_is_segmentation(*tree, g, r, {0, 0, 0});
  octomap::OcTree source(0.1);
  ASSERT_TRUE(source.readBinary(bt));
  ASSERT_EQ(source.getResolution(), tree->getResolution());
  // Each leaf sits on the source tree's key of the map voxel it came from: the source's value
  // there (unknown: 0.5) is that voxel's probability, float for float.
  std::size_t leaves = 0, agree = 0, occupied_in_source = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it, ++leaves) {
    const octomap::OcTreeKey k = it.getKey();
    std::size_t c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = static_cast<std::size_t>(std::floor((tree->keyToCoord(k[a]) - g.origin[a]) / g.voxel_size));
    const float p = g.at(c[0], c[1], c[2]);
    const octomap::OcTreeNode* n = source.search(k);
    const float want = n ? static_cast<float>(1.0 / (1.0 + std::exp(-double(n->getLogOdds())))) : 0.5f;
    agree += p == want;
    occupied_in_source += n && source.isNodeOccupied(n);
  }
  EXPECT_GT(leaves, 1000u);
  EXPECT_EQ(agree, leaves);
  // Most segment voxels are occupied in the tree; the rest are gaps the default preset closes
  // (rule 6) and the free band inside surfaces it gives to the object (rule 10): 89 % on this map.
  EXPECT_GT(occupied_in_source, leaves * 4 / 5);
}
