#include <gtest/gtest.h>

#include "occseg/params.hpp"
#include "occseg/sim/truth.hpp"
#include "sim_scenes.hpp"

using namespace occseg;
using namespace occseg::sim;

namespace {
constexpr std::uint8_t F = 0, U = 1, O = 2;
}

TEST(SimTruth, WallSceneByHand) {
  const Truth t = ground_truth(test::wall_scene(), ScanConfig());
  // Object mask: voxel centres 1.25, 1.35, 1.45, 1.55 lie in [1.23, 1.57].
  for (std::size_t x = 0; x < 20; ++x) EXPECT_EQ(t.objects[x + 20 * 5], (x >= 12 && x <= 15) ? 1 : 0) << x;
  for (std::size_t y = 0; y < 10; ++y)
    for (std::size_t x = 0; x < 20; ++x) {
      const std::uint8_t want = x < 12 ? F : x == 12 ? O : U;  // seen, first met, inside or behind
      EXPECT_EQ(t.state[x + 20 * y], want) << "(" << x << ", " << y << ")";
    }
}

TEST(SimTruth, FieldOfViewAndRangeLimitWhatIsKnown) {
  const Truth away = ground_truth(test::wall_scene(180), ScanConfig());
  for (std::size_t y = 0; y < 10; ++y) {
    EXPECT_EQ(away.state[20 * y], F) << "the sensor's own column is at +-90 degrees, in view";
    for (std::size_t x = 1; x < 20; ++x) EXPECT_EQ(away.state[x + 20 * y], U);
  }
  ScanConfig c;
  c.max_range = 0.8;
  const Truth near = ground_truth(test::wall_scene(), c);
  for (std::size_t x = 0; x < 20; ++x) EXPECT_EQ(near.state[x + 20 * 5], x <= 7 ? F : U) << x;
}

TEST(SimTruth, FullScansSeeWithinThePitchRange) {
  Scene s;
  s.name = "empty";
  s.frame.dims = Dims{10, 10, 10};
  s.frame.voxel_size = 0.1;
  Viewpoint v;
  v.position = {0.55, 0.55, 0.55};
  v.fov_deg = 360;
  s.viewpoints = {v};
  ScanConfig c;
  c.mode = ScanMode::full3d;
  const Truth t = ground_truth(s, c);
  auto at = [&](std::size_t x, std::size_t y, std::size_t z) { return t.state[x + 10 * (y + 10 * z)]; };
  EXPECT_EQ(at(9, 5, 5), F);
  EXPECT_EQ(at(9, 5, 8), F);  // pitch 36.9
  EXPECT_EQ(at(6, 5, 9), U);  // pitch 76
  EXPECT_EQ(at(5, 5, 0), U);  // straight down
  // The planar construction of the same scene sees every voxel of every layer.
  c.mode = ScanMode::planar;
  for (std::uint8_t st : ground_truth(s, c).state) EXPECT_EQ(st, F);
}

TEST(SimTruth, CatalogueScenesHaveAllThreeStates) {
  for (const std::string& n : scene_names()) {
    const Truth t = ground_truth(make_scene(n, Dims{64, 64, 16}), ScanConfig());
    std::size_t count[3] = {0, 0, 0}, objects = 0;
    for (std::uint8_t s : t.state) ++count[s];
    for (std::uint16_t o : t.objects) objects += o != 0;
    EXPECT_GT(count[F], 1000u) << n;
    EXPECT_GT(count[U], 100u) << n;
    EXPECT_GT(count[O], 50u) << n;
    EXPECT_GT(objects, 100u) << n;
    // Nothing inside a solid is free.
    for (std::size_t i = 0; i < t.state.size(); ++i)
      if (t.objects[i]) {
        ASSERT_NE(t.state[i], F) << n << " voxel " << i;
      }
  }
}
