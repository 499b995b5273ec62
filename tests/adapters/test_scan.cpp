// The PCL/OctoMap-free scan layer: boxes, fitted frames, poses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/scan_options.hpp"

using namespace occseg;

TEST(ScanFrame, GivenBoxBecomesWholeVoxels) {
  const GridFrame f = frame_for_box(Box{{-1, 0, 2}, {1, 0.5, 2.25}}, 0.1);
  EXPECT_TRUE(f.dims == (Dims{20, 5, 3})) << f.dims.nx << " " << f.dims.ny << " " << f.dims.nz;  // 0.25 -> 3
  EXPECT_DOUBLE_EQ(f.origin[0], -1);
  EXPECT_DOUBLE_EQ(f.origin[2], 2);
  try {
    frame_for_box(Box{{0, 0, 0}, {1, -1, 1}}, 0.1);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::bad_value);
    EXPECT_NE(std::string(e.what()).find("axis y"), std::string::npos) << e.what();
  }
}

TEST(ScanFrame, BoundsHoldSensorAndEndpointsClippedToMaxRange) {
  ScanBounds b;
  const float pts[] = {1, 0, 0, NAN, 0, 0, 10, 0, 0};
  b.add(make_pose({0, 0, 1}), pts, 3, 3, 4.0);  // the sensor at z = 1; 10 m return clipped to 4 m
  const GridFrame f = b.frame(0.5, 0.0);
  EXPECT_DOUBLE_EQ(f.origin[0], 0.0);
  EXPECT_DOUBLE_EQ(f.origin[2], 1.0);
  EXPECT_EQ(f.dims.nx, 9u) << "x in [0, 4] -> voxels 0..8 of 0.5 m";
  EXPECT_EQ(f.dims.nz, 1u);
  EXPECT_TRUE(ScanBounds().empty());
  EXPECT_THROW(ScanBounds().frame(0.1, 0), Error);
}

TEST(ScanFrame, PoseTransformsPointsBeforeRayCasting) {
  // A 90 degree turn about z plus a shift: sensor-frame point (1, 0, 0) lands at world
  // (2.2, 1.2, 0.1). Points stay off voxel faces so float rounding cannot move them.
  const double s = std::sqrt(0.5);
  const Eigen::Isometry3f pose = make_pose({2.2, 0.2, 0.1}, {s, 0, 0, s}).cast<float>();
  EXPECT_FALSE(is_identity(pose));
  EXPECT_TRUE(is_identity(make_pose({0, 0, 0})));
  GridFrame f = frame_for_box(Box{{0, -1, -0.5}, {4, 3, 0.5}}, 0.5);
  OccupancyFusion a(f), b(f);
  const float local[] = {1, 0, 0, 0.5f, 0, 0};
  insert_points(a, pose, local, 2, 3, 1);
  const std::vector<Vec3> world{{2.2, 1.2, 0.1}, {2.2, 0.7, 0.1}};
  b.insert_scan({2.2, 0.2, 0.1}, world, 1);
  EXPECT_EQ(a.log_odds(), b.log_odds());
  const Grid g = a.grid();
  EXPECT_NEAR(g.at(4, 4, 1), 0.7, 1e-6) << "endpoint (2.2, 1.2, 0.1) is a hit";
  EXPECT_NEAR(g.at(4, 2, 1), 0.4, 1e-6) << "the sensor voxel is passed through";
  EXPECT_THROW(make_pose({0, 0, 0}, {0, 0, 0, 0}), Error);
  EXPECT_THROW(make_pose({NAN, 0, 0}), Error);
  // Poses are doubles: an origin beyond the float range is held exactly (the fusion refuses a
  // sensor that far from the grid: ScanFrame.BoxesAndSensorsOutOfRangeAreRefusedSayingSo).
  EXPECT_EQ(make_pose({0, 1e300, 0}).translation().y(), 1e300);
  EXPECT_EQ(make_pose({-1e39, 0, 0}).translation().x(), -1e39);
}

TEST(ScanFrame, OptionsAreValidated) {
  ScanOptions o;
  o.validate();
  o.voxel_size = 0;
  EXPECT_THROW(o.validate(), Error);
  o.voxel_size = 0.1;
  o.model.p_hit = 0.4;
  EXPECT_THROW(o.validate(), Error);
}

// The norm of (1e200, 1e200, 0, 0) overflows: normalised naively it became (0, 0, 0, 0) and the
// rotation the identity. Scaled first it is the turn of 90 degrees about x that (1, 1, 0, 0) is.
TEST(ScanFrame, QuaternionsAreNormalisedWithoutOverflowOrUnderflow) {
  const Eigen::Matrix3d turn = make_pose({0, 0, 0}, {1, 1, 0, 0}).linear();
  EXPECT_NEAR(turn(2, 1), 1.0, 1e-15) << "y goes to z";
  for (double scale : {1e200, 1e-200, 1e308, 4.9e-324}) {
    const Eigen::Matrix3d r = make_pose({0, 0, 0}, {scale, scale, 0, 0}).linear();
    EXPECT_LT((r - turn).cwiseAbs().maxCoeff(), 1e-15) << scale << "\n" << r;
  }
  const Eigen::Matrix3d all = make_pose({0, 0, 0}, {1, 1, 1, 1}).linear();
  EXPECT_LT((make_pose({0, 0, 0}, {1e300, 1e300, 1e300, 1e300}).linear() - all).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_THROW(make_pose({0, 0, 0}, {0, 0, 0, 0}), Error);
  EXPECT_THROW(make_pose({0, 0, 0}, {1, INFINITY, 0, 0}), Error);
}

// Points and sensor at UTM-like coordinates: the fusion works relative to the grid corner, so
// the grid is the same as at the world origin, voxel for voxel (the shift and the coordinates
// are chosen exact in binary, so the relative coordinates are the same doubles). In float world
// coordinates (0.5 m apart at 5e6 m) it was not.
TEST(ScanFrame, FarFromTheWorldOriginTheFusionKeepsItsPrecision) {
  std::vector<float> pts;
  std::uint32_t seed = 12345;
  auto next = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  for (int i = 0; i < 3000; ++i) {  // returns 1 to 2 m away, in a cone in front of the sensor
    const double a = next() * 1.2 - 0.6, b = next() * 1.2 - 0.6, r = 1 + next();
    pts.insert(pts.end(), {float(r * std::cos(a) * std::cos(b)), float(r * std::sin(a)), float(r * std::sin(b))});
  }
  const Vec3 shift{500000, 5000000, 250};
  const std::array<double, 4> q{0.9, 0.1, -0.2, 0.3};
  const Box near{{-1.5, -2.5, -2.5}, {2.5, 2.5, 2.5}};
  const Box far{{near.min[0] + shift[0], near.min[1] + shift[1], near.min[2] + shift[2]},
                {near.max[0] + shift[0], near.max[1] + shift[1], near.max[2] + shift[2]}};
  ScanFusion a(frame_for_box(near, 0.05), SensorModel()), b(frame_for_box(far, 0.05), SensorModel());
  a.insert(make_pose({0.25, -0.125, 0.0625}, q), pts.data(), pts.size() / 3, 3, 2);
  b.insert(make_pose({0.25 + shift[0], -0.125 + shift[1], 0.0625 + shift[2]}, q), pts.data(), pts.size() / 3, 3, 1);
  const Grid ga = a.grid(), gb = b.grid();
  ASSERT_TRUE(ga.dims == gb.dims);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(gb.origin[k], ga.origin[k] + shift[k]);
  std::size_t hits = 0;
  for (float p : ga.p) hits += p > 0.5f;
  EXPECT_GT(hits, 500u);
  EXPECT_TRUE(ga.p == gb.p) << "the far grid differs";
  // A fitted frame there is just as precise: it holds every return (the same hit count).
  ScanBounds bounds;
  const Eigen::Isometry3d pose = make_pose({0.25 + shift[0], -0.125 + shift[1], 0.0625 + shift[2]}, q);
  bounds.add(pose, pts.data(), pts.size() / 3, 3, -1);
  ScanFusion c(bounds.frame(0.05, 0), SensorModel());
  c.insert(pose, pts.data(), pts.size() / 3, 3, 1);
  std::size_t fitted_hits = 0;
  for (float p : c.grid().p) fitted_hits += p > 0.5f;
  EXPECT_NEAR(double(fitted_hits), double(hits), 0.01 * hits);
}

// Beyond 2^40 voxels from the world origin, coordinates are refused as out of range: before, a
// sensor at 1e30 m gave a fitted box of "dimensions 0 x 61 x 81", which "have a zero".
TEST(ScanFrame, BoxesAndSensorsOutOfRangeAreRefusedSayingSo) {
  auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::bad_value) << e.what();
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const float pts[] = {1, 0, 0, 0, 1, 0};
  ScanBounds b;
  b.add(make_pose({1e30, 0, 0}), pts, 2, 3, -1);
  std::string m = message([&] { b.frame(0.05, 0); });
  EXPECT_NE(m.find("out of range"), std::string::npos) << m;
  EXPECT_NE(m.find("x = 1e+30"), std::string::npos) << m;
  m = message([] { frame_for_box(Box{{1e15, 0, 0}, {1e15 + 1, 1, 1}}, 0.05); });
  EXPECT_NE(m.find("out of range"), std::string::npos) << m;
  ScanFusion f(frame_for_box(Box{{0, 0, 0}, {1, 1, 1}}, 0.05), SensorModel());
  m = message([&] { f.insert(make_pose({0, -1e20, 0}), pts, 2, 3, 1); });
  EXPECT_NE(m.find("sensor origin at y = -1e+20"), std::string::npos) << m;
  // Within range it is fine: 2^40 voxels of 0.05 m are 5.5e10 m.
  ScanBounds ok;
  ok.add(make_pose({5e10, 0, 0}), pts, 2, 3, -1);
  EXPECT_NO_THROW(ok.frame(0.05, 0));
}
