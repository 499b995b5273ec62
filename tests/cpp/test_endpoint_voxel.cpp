// endpoint_voxel (occseg/fusion.hpp): the voxel of a point is the voxel the fusion put its return
// in, for rays from inside and outside the grid, points on voxel faces and outside the box.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "occseg/fusion.hpp"

using namespace occseg;

namespace {

GridFrame frame(std::size_t nx, std::size_t ny, std::size_t nz, double vs, Vec3 origin) {
  GridFrame f;
  f.dims = Dims{nx, ny, nz};
  f.voxel_size = vs;
  f.origin = origin;
  return f;
}

}  // namespace

// One ray per scan, so the voxel holding a hit is exactly the voxel of that ray's return: every
// return the fusion marked as a hit is the voxel endpoint_voxel names, and no other voxel is hit.
TEST(EndpointVoxel, IsTheVoxelTheFusionPutTheReturnIn) {
  const GridFrame f = frame(23, 17, 11, 0.07, {-0.4, 0.3, -1.1});
  std::mt19937 rng(26);
  std::uniform_real_distribution<double> ux(-0.6, 23 * 0.07 - 0.2), uy(0.1, 0.3 + 17 * 0.07 + 0.2),
      uz(-1.3, -1.1 + 11 * 0.07 + 0.2);
  int inside = 0, outside = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3 sensor{ux(rng), uy(rng), uz(rng)};
    float p[3] = {static_cast<float>(ux(rng)), static_cast<float>(uy(rng)), static_cast<float>(uz(rng))};
    if (k % 7 == 0) p[k % 3] = static_cast<float>(f.origin[k % 3] + f.voxel_size * (k % 5));  // on a face
    OccupancyFusion fu(f);
    fu.insert_scan(sensor, p, 1, 3, 1);
    std::uint64_t v = 0;
    const bool found = endpoint_voxel(f, sensor, p, v);
    std::uint64_t hits = 0, hit = 0;
    for (std::size_t i = 0; i < fu.log_odds().size(); ++i)
      if (fu.log_odds()[i] > 0) ++hits, hit = i;
    if (found) {
      ++inside;
      ASSERT_LT(v, f.dims.count());
      ASSERT_EQ(hits, 1u) << k;
      EXPECT_EQ(hit, v) << k;
    } else {
      ++outside;
      EXPECT_EQ(hits, 0u) << k << ": a hit for a point outside the grid";
    }
  }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 20);
}

TEST(EndpointVoxel, NonFinitePointsAndPointsOutsideHaveNone) {
  const GridFrame f = frame(4, 4, 4, 0.5, {0, 0, 0});
  std::uint64_t v = 77;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float a[3] = {nan, 1, 1}, b[3] = {1, inf, 1}, c[3] = {3, 1, 1}, d[3] = {1, 1, -0.01f}, e[3] = {1.2f, 0.1f, 1.9f};
  EXPECT_FALSE(endpoint_voxel(f, {1, 1, 1}, a, v));
  EXPECT_FALSE(endpoint_voxel(f, {1, 1, 1}, b, v));
  EXPECT_FALSE(endpoint_voxel(f, {1, 1, 1}, c, v));
  EXPECT_FALSE(endpoint_voxel(f, {1, 1, 1}, d, v));
  EXPECT_EQ(v, 77u) << "untouched";
  ASSERT_TRUE(endpoint_voxel(f, {1, 1, 1}, e, v));
  EXPECT_EQ(v, 2u + 4u * (0u + 4u * 3u));
  ASSERT_TRUE(endpoint_voxel(f, {-5, 9, 1}, e, v)) << "the sensor may lie outside";
  EXPECT_EQ(v, 2u + 4u * (0u + 4u * 3u));
}
