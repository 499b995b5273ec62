// The PCL/OctoMap-free scan layer: boxes, fitted frames, poses.
#include <gtest/gtest.h>

#include <cmath>

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
