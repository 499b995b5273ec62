// liboccseg_octomap: .bt/.ot trees and .graph scan graphs. Real data: the OctoMap corridor
// geb079.bt and spherical_scan.graph from ../shared/data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include "occseg/error.hpp"
#include "occseg/octomap_file.hpp"
#include "occseg/octomap_tree.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {
const std::string kBt = std::string(OCCSEG_SHARED_DATA) + "/geb079.bt";
const std::string kGraph = std::string(OCCSEG_SHARED_DATA) + "/spherical_scan.graph";

std::string tmp(const std::string& name) {
  fs::create_directories(OCCSEG_TEST_TMP);
  return std::string(OCCSEG_TEST_TMP) + "/" + name;
}
std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void put(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }
Status status_of(const std::function<void()>& f, std::string* msg = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (msg) *msg = e.what();
    return e.status();
  }
  return Status::ok;
}
const octomap::OcTree& corridor() {
  static octomap::OcTree* t = [] {
    auto* tree = new octomap::OcTree(0.1);
    tree->readBinary(kBt);
    return tree;
  }();
  return *t;
}
// The voxel of grid g holding world point (x, y, z).
float at_world(const Grid& g, double x, double y, double z) {
  const double w[3] = {x, y, z};
  std::size_t c[3];
  for (int k = 0; k < 3; ++k) c[k] = static_cast<std::size_t>(std::floor((w[k] - g.origin[k]) / g.voxel_size));
  return g.at(c[0], c[1], c[2]);
}
}  // namespace

TEST(OctomapBt, CorridorBoundsAndCountsMatchTheTree) {
  const octomap::OcTree& tree = corridor();
  ASSERT_DOUBLE_EQ(tree.getResolution(), 0.08);
  ASSERT_EQ(tree.size(), 532566u) << "the data README's node count";
  const Grid g = read_octree_file(kBt);
  // The box is the tree's own metric bounding box.
  double x0, y0, z0, x1, y1, z1;
  const_cast<octomap::OcTree&>(tree).getMetricMin(x0, y0, z0);
  const_cast<octomap::OcTree&>(tree).getMetricMax(x1, y1, z1);
  EXPECT_NEAR(g.origin[0], x0, 1e-9);
  EXPECT_NEAR(g.origin[1], y0, 1e-9);
  EXPECT_NEAR(g.origin[2], z0, 1e-9);
  EXPECT_NEAR(g.origin[0] + g.dims.nx * 0.08, x1, 1e-6);
  EXPECT_NEAR(g.origin[1] + g.dims.ny * 0.08, y1, 1e-6);
  EXPECT_NEAR(g.origin[2] + g.dims.nz * 0.08, z1, 1e-6);
  EXPECT_TRUE(g.dims == (Dims{487, 187, 39})) << g.dims.nx << " " << g.dims.ny << " " << g.dims.nz;
  // Voxel counts per state against the tree's leaves (a leaf at depth d is (2^(16-d))^3 voxels).
  std::uint64_t occ = 0, fr = 0;
  for (auto it = tree.begin_leafs(16), end = tree.end_leafs(); it != end; ++it) {
    const std::uint64_t side = std::uint64_t(1) << (16 - it.getDepth());
    (tree.isNodeOccupied(*it) ? occ : fr) += side * side * side;
  }
  std::uint64_t g_occ = 0, g_free = 0, g_unknown = 0;
  for (float p : g.p) {
    if (p > 0.5f) ++g_occ;
    else if (p < 0.5f) ++g_free;
    else ++g_unknown;
  }
  EXPECT_EQ(g_occ, occ);
  EXPECT_EQ(g_free, fr);
  EXPECT_EQ(g_occ + g_free + g_unknown, g.dims.count());
  // Maximum likelihood: exactly the two clamping values (0.1192 and 0.971).
  for (float p : g.p) ASSERT_TRUE(p == 0.5f || std::fabs(p - 0.971f) < 1e-4f || std::fabs(p - 0.1192f) < 1e-4f) << p;
  // Every 101st voxel against the tree's own lookup.
  for (std::size_t i = 0; i < g.p.size(); i += 101) {
    const std::size_t x = i % g.dims.nx, y = (i / g.dims.nx) % g.dims.ny, z = i / (g.dims.nx * g.dims.ny);
    const octomap::OcTreeNode* n = tree.search(g.origin[0] + (x + 0.5) * 0.08, g.origin[1] + (y + 0.5) * 0.08,
                                               g.origin[2] + (z + 0.5) * 0.08);
    const float want = n ? static_cast<float>(n->getOccupancy()) : 0.5f;
    ASSERT_NEAR(g.p[i], want, 1e-6) << x << " " << y << " " << z;
  }
}

TEST(OctomapBt, CoarserVoxelsFollowTheDocumentedRules) {
  OctreeOptions fine_o;
  fine_o.bbox = Box{{0, -2, 0}, {4, 2, 1.5}};
  const Grid fine = read_octree_file(kBt, fine_o);
  EXPECT_NEAR(fine.origin[0], 0, 1e-9);
  EXPECT_NEAR(fine.origin[1], -2, 1e-9);
  EXPECT_TRUE(fine.dims == (Dims{50, 50, 19})) << "1.5 m -> 19 voxels of 8 cm";
  OctreeOptions o = fine_o;
  o.voxel_size = 0.24;  // 3 tree voxels per edge
  const Grid cmax = read_octree_file(kBt, o);
  o.coarsen = Coarsen::mean;
  const Grid cmean = read_octree_file(kBt, o);
  ASSERT_TRUE(cmax.dims == (Dims{17, 17, 7}));
  EXPECT_DOUBLE_EQ(cmax.voxel_size, 0.24);
  std::size_t mixed = 0;
  // Recompute from the fine grid: max of known children, or mean of known children.
  for (std::size_t z = 0; z < 7; ++z)
    for (std::size_t y = 0; y < 17; ++y)
      for (std::size_t x = 0; x < 17; ++x) {
        float mx = -1;
        double sum = 0;
        int known = 0;
        // The coarse box reaches past the fine one (17 * 3 > 50): look those voxels up in the tree.
        for (int dz = 0; dz < 3; ++dz)
          for (int dy = 0; dy < 3; ++dy)
            for (int dx = 0; dx < 3; ++dx) {
              const std::size_t fx = 3 * x + dx, fy = 3 * y + dy, fz = 3 * z + dz;
              float p = 0.5f;
              if (fx < 50 && fy < 50 && fz < 19) {
                p = fine.at(fx, fy, fz);
              } else {
                const octomap::OcTreeNode* n = corridor().search(fine.origin[0] + (fx + 0.5) * 0.08,
                                                                 fine.origin[1] + (fy + 0.5) * 0.08,
                                                                 fine.origin[2] + (fz + 0.5) * 0.08);
                if (n) p = static_cast<float>(n->getOccupancy());
              }
              if (p == 0.5f) continue;
              ++known;
              mx = std::max(mx, p);
              sum += p;
            }
        mixed += known && sum / known > 0.2 && sum / known < 0.9;
        ASSERT_NEAR(cmax.at(x, y, z), known ? mx : 0.5f, 1e-6) << x << " " << y << " " << z;
        ASSERT_NEAR(cmean.at(x, y, z), known ? sum / known : 0.5, 1e-5) << x << " " << y << " " << z;
      }
  EXPECT_GT(mixed, 10u) << "the rules differ somewhere";
  o.voxel_size = 0.1;
  EXPECT_EQ(status_of([&] { read_octree_file(kBt, o); }), Status::invalid_argument) << "0.1 is not k * 0.08";
}

TEST(OctomapOt, GradedLogOddsSurviveAndMatchOctomapsOwnLookup) {
  // A tree with graded values: OctoMap's own insertPointCloud of the real scan graph, then every
  // third point again from a sensor 0.3 m to the side, so voxels see 1, 2 or 3 updates.
  octomap::ScanGraph graph;
  ASSERT_TRUE(graph.readBinary(kGraph));
  octomap::OcTree tree(0.1);
  for (const octomap::ScanNode* n : graph) {
    tree.insertPointCloud(*n, -1, false, false);
    octomap::Pointcloud some;
    for (std::size_t i = 0; i < n->scan->size(); i += 3) some.push_back(n->pose.transform((*n->scan)[i]));
    tree.insertPointCloud(some, n->pose.trans() + octomap::point3d(0, 0.3f, 0));
    tree.insertPointCloud(some, n->pose.trans());
  }
  const std::string f = tmp("spherical.ot");
  ASSERT_TRUE(tree.write(f));
  const Grid g = read_octree_file(f);
  std::set<float> values(g.p.begin(), g.p.end());
  EXPECT_GT(values.size(), 3u) << ".ot keeps more than the two clamping values";
  std::size_t known = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    ASSERT_NEAR(at_world(g, it.getX(), it.getY(), it.getZ()), it->getOccupancy(), 1e-6);
    ++known;
  }
  EXPECT_GT(known, 1000u);
  // The same tree in memory.
  const Grid m = grid_from_octree(tree);
  EXPECT_EQ(m.p, g.p);
}

TEST(OctomapGraph, SphericalScanFusedLikeOctomap) {
  ScanOptions o;
  o.voxel_size = 0.1;
  // A box on OctoMap's voxel grid (faces at multiples of 0.1 m) so voxels coincide.
  o.bbox = Box{{0.5, -2.0, -2.5}, {5.5, 2.0, 1.5}};
  const Grid g = read_scan_graph(kGraph, o);
  ASSERT_TRUE(g.dims == (Dims{50, 40, 40}));
  octomap::ScanGraph graph;
  ASSERT_TRUE(graph.readBinary(kGraph));
  ASSERT_EQ(graph.size(), 1u);
  octomap::OcTree tree(0.1);
  for (const octomap::ScanNode* n : graph) tree.insertPointCloud(*n, -1, false, false);
  // The sensor pose (1, 0, -0.5) from the graph: its voxel is passed by every ray.
  EXPECT_LT(at_world(g, 1.05, 0.05, -0.45), 0.5f);
  // State agreement with OctoMap voxel by voxel (the two DDA implementations differ only where
  // a ray grazes a voxel corner).
  std::size_t both = 0, agree = 0, occ = 0;
  for (std::size_t z = 0; z < 40; ++z)
    for (std::size_t y = 0; y < 40; ++y)
      for (std::size_t x = 0; x < 50; ++x) {
        const double cx = g.origin[0] + (x + 0.5) * 0.1, cy = g.origin[1] + (y + 0.5) * 0.1,
                     cz = g.origin[2] + (z + 0.5) * 0.1;
        const octomap::OcTreeNode* n = tree.search(cx, cy, cz);
        const float p = g.at(x, y, z);
        if (!n && p == 0.5f) continue;
        ++both;
        const int mine = p > 0.5f ? 2 : (p < 0.5f ? 0 : 1);
        const int theirs = n ? (n->getOccupancy() > 0.5 ? 2 : 0) : 1;
        agree += mine == theirs;
        occ += mine == 2;
      }
  std::printf("spherical scan: %zu of %zu observed voxels agree with OctoMap, %zu occupied\n", agree, both, occ);
  EXPECT_GT(occ, 500u);
  EXPECT_GE(double(agree) / both, 0.995) << agree << " of " << both;
}

TEST(OctomapFiles, BadFilesGiveStatusesNamingTheFile) {
  std::string msg;
  EXPECT_EQ(status_of([&] { read_octree_file(tmp("missing.bt")); }, &msg), Status::io);
  EXPECT_NE(msg.find("missing.bt"), std::string::npos);
  const std::string bt = slurp(kBt);
  const std::string f = tmp("cut.bt");
  put(f, bt.substr(0, bt.size() - 1000));
  EXPECT_EQ(status_of([&] { read_octree_file(f); }, &msg), Status::format);
  EXPECT_NE(msg.find("cut.bt"), std::string::npos) << msg;
  std::string flipped = bt;
  flipped[bt.size() / 2] = static_cast<char>(0xff);  // every child an inner node
  put(f, flipped);
  EXPECT_EQ(status_of([&] { read_octree_file(f); }, &msg), Status::format) << msg;
  put(f, "# Octomap OcTree binary file\nid OcTree\nsize 5\nres 0.1\n");
  EXPECT_EQ(status_of([&] { read_octree_file(f); }), Status::format) << "no data line";
  put(f, "# Octomap OcTree file\nid CountingOcTree\nsize 1\nres 0.1\ndata\n");
  EXPECT_EQ(status_of([&] { read_octree_file(f); }), Status::unsupported);
  put(f, "hello\n");
  EXPECT_EQ(status_of([&] { read_octree_file(f); }), Status::format);
  // Scan graphs: cut, a lying point count, stray bytes.
  const std::string graph = slurp(kGraph);
  const std::string g = tmp("bad.graph");
  ScanOptions o;
  o.voxel_size = 0.2;
  put(g, graph.substr(0, graph.size() - 10));
  EXPECT_EQ(status_of([&] { read_scan_graph(g, o); }, &msg), Status::format);
  EXPECT_NE(msg.find("bad.graph"), std::string::npos) << msg;
  std::string big = graph;
  big[7] = static_cast<char>(0x7f);  // point count ~2^31: checked before anything is allocated
  put(g, big);
  EXPECT_EQ(status_of([&] { read_scan_graph(g, o); }), Status::format);
  put(g, graph + "xx");
  EXPECT_EQ(status_of([&] { read_scan_graph(g, o); }), Status::format);
  EXPECT_EQ(status_of([&] { read_scan_graph(tmp("missing.graph"), o); }), Status::io);
}

TEST(OctomapOt, StampedTreesAreReadLikeTheOtherTypes) {
  // OcTreeStamped nodes are written as plain OcTreeNodes (log-odds only, no time stamp): the
  // structure check once expected 8 bytes a node and refused every such file OctoMap wrote.
  octomap::OcTreeStamped tree(0.1);
  for (int i = -6; i <= 6; ++i) tree.updateNode(octomap::point3d(0.1f * i, 0.05f, 0.2f), float(0.3 * i));
  tree.updateInnerOccupancy();
  const std::string f = tmp("stamped.ot");
  ASSERT_TRUE(tree.write(f));
  std::string msg;
  Grid g;
  ASSERT_EQ(status_of([&] { g = read_octree_file(f); }, &msg), Status::ok) << msg;
  const Grid m = grid_from_octree(tree);
  EXPECT_TRUE(g.dims == m.dims);
  EXPECT_EQ(g.p, m.p);
}

TEST(OctomapBt, HugeOrFarBoxesAndVoxelSizesAreRefusedBeforeAnyIntegerConversion) {
  // A box of 1e300 m once overflowed the conversion to tree keys (undefined behaviour): a
  // one-voxel map at -7e17 m and exit 0. The .pcd path already refused it (frame_for_box).
  std::string msg;
  OctreeOptions o;
  o.bbox = Box{{-1e300, -1e300, -1e300}, {1e300, 1e300, 1e300}};
  EXPECT_EQ(status_of([&] { read_octree_file(kBt, o); }, &msg), Status::bad_dims);
  EXPECT_NE(msg.find("bounding box needs too many voxels of 0.08"), std::string::npos) << msg;
  EXPECT_NE(msg.find("geb079.bt"), std::string::npos) << msg;
  o.bbox = Box{{1e300, 1e300, 1e300}, {1.0000001e300, 1.0000001e300, 1.0000001e300}};
  EXPECT_EQ(status_of([&] { read_octree_file(kBt, o); }, &msg), Status::bad_dims);
  o.bbox = Box{{1e17, 0, 0}, {1e17 + 1e3, 1, 1}};  // few voxels, but 10^18 keys from the origin
  EXPECT_EQ(status_of([&] { read_octree_file(kBt, o); }, &msg), Status::bad_dims);
  EXPECT_NE(msg.find("from the origin"), std::string::npos) << msg;
  // A far box of a sane size still reads: all unknown.
  o.bbox = Box{{1e6, 0, 0}, {1e6 + 0.8, 0.8, 0.8}};
  Grid g;
  ASSERT_EQ(status_of([&] { g = read_octree_file(kBt, o); }, &msg), Status::ok) << msg;
  EXPECT_TRUE(g.dims == (Dims{10, 10, 10})) << g.dims.nx;
  EXPECT_NEAR(g.origin[0], 1e6, 0.08);
  for (float p : g.p) ASSERT_EQ(p, 0.5f);
  // A voxel size whose ratio to the resolution does not fit an integer.
  OctreeOptions v;
  v.voxel_size = 1e300;
  EXPECT_EQ(status_of([&] { read_octree_file(kBt, v); }, &msg), Status::invalid_argument);
  EXPECT_NE(msg.find("multiple"), std::string::npos) << msg;
}
