#include <gtest/gtest.h>

#include <cmath>

#include "occseg/error.hpp"
#include "occseg/fusion.hpp"

using namespace occseg;

namespace {
GridFrame frame(std::size_t nx, std::size_t ny, std::size_t nz, double vs = 0.1) {
  GridFrame f;
  f.dims = Dims{nx, ny, nz};
  f.voxel_size = vs;
  return f;
}
}  // namespace

TEST(Fusion, OneRayAlongX) {
  OccupancyFusion fu(frame(10, 3, 3));
  // From the centre of voxel (0,1,1) to the centre of voxel (6,1,1).
  fu.insert_scan({0.05, 0.15, 0.15}, std::vector<Vec3>{{0.65, 0.15, 0.15}}, 1);
  const Grid g = fu.grid();
  for (int x = 0; x < 6; ++x) EXPECT_NEAR(g.at(x, 1, 1), 0.4, 1e-6) << x;
  EXPECT_NEAR(g.at(6, 1, 1), 0.7, 1e-6);
  for (int x = 7; x < 10; ++x) EXPECT_EQ(g.at(x, 1, 1), 0.5f) << "nothing beyond the return";
  EXPECT_EQ(g.at(3, 0, 1), 0.5f) << "never observed: exactly 0.5";
  EXPECT_EQ(fu.rays(), 1u);
}

TEST(Fusion, RepeatedHitsTendToTheClampingValues) {
  OccupancyFusion fu(frame(8, 1, 1));
  for (int k = 0; k < 30; ++k) fu.insert_scan({0.05, 0.05, 0.05}, std::vector<Vec3>{{0.55, 0.05, 0.05}}, 1);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(5, 0, 0), 0.97, 1e-5);
  EXPECT_NEAR(g.at(2, 0, 0), 0.12, 1e-5);
  // After exactly two scans the log-odds add: logit^-1(2 logit 0.7).
  OccupancyFusion two(frame(8, 1, 1));
  for (int k = 0; k < 2; ++k) two.insert_scan({0.05, 0.05, 0.05}, std::vector<Vec3>{{0.55, 0.05, 0.05}}, 1);
  const double l = 2 * std::log(0.7 / 0.3);
  EXPECT_NEAR(two.grid().at(5, 0, 0), 1 / (1 + std::exp(-l)), 1e-6);
}

TEST(Fusion, HitWinsOverMissWithinAScanAndNaNIsSkipped) {
  OccupancyFusion fu(frame(8, 1, 1));
  const float nan = std::nanf("");
  // Ray 1 passes through voxel 3, ray 2 ends in it: hit, once.
  const float xyz[9] = {0.65f, 0.05f, 0.05f, 0.35f, 0.05f, 0.05f, nan, 0.0f, 0.0f};
  fu.insert_scan({0.05, 0.05, 0.05}, xyz, 3, 3, 2);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(3, 0, 0), 0.7, 1e-6);
  EXPECT_NEAR(g.at(2, 0, 0), 0.4, 1e-6);
  EXPECT_EQ(fu.rays(), 2u);
}

TEST(Fusion, MaxRangeMarksFreeSpaceOnly) {
  SensorModel m;
  m.max_range = 0.3;
  OccupancyFusion fu(frame(10, 1, 1), m);
  fu.insert_scan({0.05, 0.05, 0.05}, std::vector<Vec3>{{0.85, 0.05, 0.05}}, 1);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(0, 0, 0), 0.4, 1e-6);
  EXPECT_NEAR(g.at(3, 0, 0), 0.4, 1e-6);  // truncated at 0.35 m: voxel 3 is the last one crossed
  EXPECT_EQ(g.at(4, 0, 0), 0.5f);
  EXPECT_EQ(g.at(8, 0, 0), 0.5f) << "no hit at a max-range return";
}

TEST(Fusion, SensorOutsideTheGridIsClipped) {
  OccupancyFusion fu(frame(5, 5, 1));
  fu.insert_scan({-1.0, 0.25, 0.05}, std::vector<Vec3>{{0.25, 0.25, 0.05}}, 1);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(0, 2, 0), 0.4, 1e-6);
  EXPECT_NEAR(g.at(1, 2, 0), 0.4, 1e-6);
  EXPECT_NEAR(g.at(2, 2, 0), 0.7, 1e-6);
  EXPECT_EQ(g.at(3, 2, 0), 0.5f);
  // A ray that misses the box entirely changes nothing.
  OccupancyFusion miss(frame(5, 5, 1));
  miss.insert_scan({-1.0, 5.0, 0.05}, std::vector<Vec3>{{-0.5, 6.0, 0.05}}, 1);
  for (float v : miss.grid().p) EXPECT_EQ(v, 0.5f);
}

TEST(Fusion, DiagonalRayIsFaceConnected) {
  OccupancyFusion fu(frame(20, 20, 20));
  fu.insert_scan({0.01, 0.02, 0.03}, std::vector<Vec3>{{1.93, 1.71, 1.55}}, 1);
  const Grid g = fu.grid();
  int touched = 0;
  for (float v : g.p) touched += v != 0.5f;
  // A 6-connected walk from voxel (0,0,0) to (19,17,15) visits 19+17+15+1 voxels.
  EXPECT_EQ(touched, 19 + 17 + 15 + 1);
  EXPECT_NEAR(g.at(19, 17, 15), 0.7, 1e-6);
}

TEST(Fusion, ThreadsDoNotChangeTheMap) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 2000; ++i)
    pts.push_back({2.0 + std::cos(i * 0.01) * 1.5, 2.0 + std::sin(i * 0.01) * 1.5, 0.2 + (i % 7) * 0.3});
  OccupancyFusion a(frame(40, 40, 30)), b(frame(40, 40, 30));
  a.insert_scan({2.0, 2.0, 1.0}, pts, 1);
  b.insert_scan({2.0, 2.0, 1.0}, pts, 4);
  EXPECT_EQ(a.log_odds(), b.log_odds());
}

TEST(Fusion, FitFrameAndBadInput) {
  const GridFrame f = fit_frame({{0.01, 0.02, 0.03}, {0.29, -0.11, 0.03}}, 0.1);
  EXPECT_EQ(f.dims, (Dims{3, 3, 1}));
  EXPECT_NEAR(f.origin[1], -0.2, 1e-12);
  EXPECT_THROW(fit_frame({}, 0.1), Error);
  SensorModel bad;
  bad.p_hit = 0.3;
  EXPECT_THROW(OccupancyFusion(frame(2, 2, 2), bad), Error);
  OccupancyFusion fu(frame(2, 2, 2));
  EXPECT_THROW(fu.insert_scan({NAN, 0, 0}, std::vector<Vec3>{{0, 0, 0}}, 1), Error);
}

// Progress (the `occseg` progress bar and Ctrl-C hang on it): reports after every 65536 rays,
// changes nothing in the map, and a cancel leaves the grid as the earlier scans made it.
namespace {
std::vector<Vec3> ring(std::size_t n, double z) {
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < n; ++i)
    pts.push_back({2.0 + std::cos(i * 1e-4) * 1.5, 2.0 + std::sin(i * 1e-4) * 1.5, z + (i % 5) * 0.2});
  return pts;
}
}  // namespace

TEST(Fusion, ProgressReportsEveryChunkAndChangesNothing) {
  const std::vector<Vec3> pts = ring(200000, 0.3);
  OccupancyFusion plain(frame(40, 40, 30)), watched(frame(40, 40, 30));
  std::vector<std::size_t> done;
  watched.set_progress([&](std::size_t d, std::size_t count) {
    EXPECT_EQ(count, pts.size());
    done.push_back(d);
    return true;
  });
  plain.insert_scan({2.0, 2.0, 1.0}, pts, 2);
  watched.insert_scan({2.0, 2.0, 1.0}, pts, 2);
  EXPECT_EQ(done, (std::vector<std::size_t>{65536, 131072, 196608, 200000}));
  EXPECT_EQ(plain.log_odds(), watched.log_odds());
}

TEST(Fusion, CancelledScanLeavesTheEarlierOnes) {
  OccupancyFusion fu(frame(40, 40, 30)), once(frame(40, 40, 30));
  fu.insert_scan({2.0, 2.0, 1.0}, ring(1000, 0.3), 1);
  once.insert_scan({2.0, 2.0, 1.0}, ring(1000, 0.3), 1);
  int calls = 0;
  fu.set_progress([&](std::size_t, std::size_t) { return ++calls < 2; });
  try {
    fu.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 2);
    FAIL() << "no cancel";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::cancelled);
  }
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(fu.scans(), 1u);
  EXPECT_EQ(fu.log_odds(), once.log_odds());
  // Usable afterwards: the same scan again, now to the end, gives what a fresh fusion gives.
  fu.set_progress({});
  fu.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 2);
  once.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 2);
  EXPECT_EQ(fu.log_odds(), once.log_odds());
}
