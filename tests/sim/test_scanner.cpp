#include <gtest/gtest.h>

#include <cmath>

#include "occseg/error.hpp"
#include "occseg/sim/scanner.hpp"
#include "sim_scenes.hpp"

using namespace occseg;
using namespace occseg::sim;

TEST(SimScanner, RayFansFollowTheAngularStep) {
  Viewpoint v;
  v.heading_deg = 90;
  const auto fan = ray_directions(v, ScanMode::planar, 0.5);
  ASSERT_EQ(fan.size(), 361u);  // 180 degrees at 0.5 degrees, both ends included
  EXPECT_NEAR(fan.front()[0], 1.0, 1e-12);   // heading - 90 = 0 degrees: +x
  EXPECT_NEAR(fan.back()[0], -1.0, 1e-12);   // heading + 90 = 180 degrees: -x
  EXPECT_NEAR(fan[180][1], 1.0, 1e-12);      // the middle ray looks along the heading
  EXPECT_NEAR(std::acos(fan[0][0] * fan[1][0] + fan[0][1] * fan[1][1]), 0.5 * M_PI / 180, 1e-12);
  v.fov_deg = 360;
  EXPECT_EQ(ray_directions(v, ScanMode::planar, 0.5).size(), 720u);
  v.fov_deg = 180;
  const auto full = ray_directions(v, ScanMode::full3d, 0.5);
  EXPECT_EQ(full.size(), 361u * 181u);  // pitch -45..45
  EXPECT_NEAR(full.front()[2], -std::sqrt(0.5), 1e-12);
  for (const Vec3& d : full) EXPECT_TRUE(in_view(v, ScanMode::full3d, d));
  EXPECT_FALSE(in_view(v, ScanMode::planar, {0, -1, 0}));
  EXPECT_FALSE(in_view(v, ScanMode::full3d, {0, 0.5, 0.8660254}));  // pitch 60
  EXPECT_FALSE(in_view(v, ScanMode::planar, {0, 0.99, 0.1}));       // not horizontal
}

TEST(SimScanner, RangeToAKnownPlaneIsRightOnAverageWithTheRequestedSigma) {
  const Scene s = test::wall_scene();
  ScanConfig c;  // sigma 4 cm
  Rng rng(5);
  const int n = 20000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double r = measure_range(s, {0.05, 0.5, 0.05}, {1, 0, 0}, c, rng);
    sum += r;
    sum2 += r * r;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 1.18, 4 * 0.04 / std::sqrt(n));
  EXPECT_NEAR(sd, 0.04, 0.04 * 4 / std::sqrt(2.0 * n));
  // An oblique ray at 45 degrees meets the plane at 1.18 sqrt 2.
  c.range_sigma = 0;
  EXPECT_NEAR(measure_range(s, {0.05, 0.5, 0.05}, {std::sqrt(0.5), std::sqrt(0.5), 0}, c, rng), 1.18 * std::sqrt(2.0),
              1e-12);
  c.max_range = 1.0;
  EXPECT_TRUE(std::isnan(measure_range(s, {0.05, 0.5, 0.05}, {1, 0, 0}, c, rng))) << "beyond max range";
}

TEST(SimScanner, NoiseFreeMapIsFreeToTheWallOccupiedAtItAndUntouchedBehind) {
  ScanConfig c;
  c.range_sigma = 0;
  const Grid g = simulate_map(test::wall_scene(), c);
  for (std::size_t y : {4u, 5u}) {
    for (std::size_t x = 0; x < 12; ++x) EXPECT_LT(g.at(x, y, 0), 0.5f) << x;
    EXPECT_NEAR(g.at(12, y, 0), 0.7f, 1e-6) << "one hit";
    for (std::size_t x = 13; x < 20; ++x) EXPECT_EQ(g.at(x, y, 0), 0.5f) << "never observed: exactly 0.5";
  }
}

TEST(SimScanner, UnobservedVoxelsStayExactlyHalf) {
  ScanConfig c;  // 4 cm noise: nothing reaches 0.3 m (7 sigma) behind the face
  const Grid g = simulate_map(test::wall_scene(), c);
  for (std::size_t y = 0; y < 10; ++y)
    for (std::size_t x = 16; x < 20; ++x) EXPECT_EQ(g.at(x, y, 0), 0.5f);
  // Looking away (-x): only the sensor's own column is in the fan.
  const Grid away = simulate_map(test::wall_scene(180), c);
  for (std::size_t y = 0; y < 10; ++y)
    for (std::size_t x = 1; x < 20; ++x) EXPECT_EQ(away.at(x, y, 0), 0.5f);
  EXPECT_LT(away.at(0, 5, 0), 0.5f);
}

TEST(SimScanner, MapsDependOnTheSeedOnly) {
  const Scene s = make_scene("cone", Dims{48, 48, 16}, 0.04);
  for (ScanMode m : {ScanMode::planar, ScanMode::full3d}) {
    ScanConfig c;
    c.mode = m;
    c.threads = 1;
    const Grid a = simulate_map(s, c);
    c.threads = 3;
    const Grid b = simulate_map(s, c);
    EXPECT_EQ(a.p, b.p) << scan_mode_name(m);
    c.seed = 2;
    EXPECT_NE(simulate_map(s, c).p, a.p) << scan_mode_name(m);
    std::size_t seen = 0, hit = 0;
    for (float p : a.p) {
      seen += p != 0.5f;
      hit += p > 0.5f;
    }
    EXPECT_GT(seen, a.p.size() / 2) << scan_mode_name(m);
    EXPECT_GT(hit, 100u) << scan_mode_name(m);
  }
}

TEST(SimScanner, BadConfigAndScenesAreRejected) {
  ScanConfig c;
  c.range_sigma = -1;
  EXPECT_THROW(c.validate(), Error);
  c = ScanConfig();
  c.angle_step_deg = 0;
  EXPECT_THROW(simulate_map(test::wall_scene(), c), Error);
  Scene s = test::wall_scene();
  s.viewpoints.clear();
  EXPECT_THROW(simulate_map(s, ScanConfig()), Error);
  EXPECT_THROW(make_scene("pyramid"), Error);
  EXPECT_THROW(make_scene("cone", Dims{8, 8, 8}), Error);
  for (const std::string& n : scene_names()) EXPECT_NO_THROW(make_scene(n, Dims{64, 64, 16}));
}

// ScanConfig::progress (the `occseg demo` progress bar and Ctrl-C): one report per planar layer,
// in order, ending at 1; the same map as without it; false cancels.
TEST(SimScanner, ProgressCountsLayersAndCancels) {
  const Scene s = make_scene("cone", Dims{48, 48, 16}, 0.04);
  ScanConfig c;
  c.threads = 3;
  const Grid plain = simulate_map(s, c);
  std::vector<double> seen;
  c.progress = [&](double f) {
    seen.push_back(f);
    return true;
  };
  EXPECT_EQ(simulate_map(s, c).p, plain.p);
  ASSERT_EQ(seen.size(), 16u);
  for (std::size_t k = 0; k < seen.size(); ++k) EXPECT_DOUBLE_EQ(seen[k], double(k + 1) / 16);
  c.progress = [](double f) { return f < 0.25; };
  try {
    simulate_map(s, c);
    FAIL() << "no cancel";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::cancelled);
  }
  c.mode = ScanMode::full3d;  // one fusion: reports within each viewpoint's scan
  seen.clear();
  c.progress = [&](double f) {
    seen.push_back(f);
    return true;
  };
  EXPECT_EQ(simulate_map(s, c).p, [&] { ScanConfig d = c; d.progress = {}; return simulate_map(s, d).p; }());
  ASSERT_FALSE(seen.empty());
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
  for (std::size_t k = 1; k < seen.size(); ++k) EXPECT_LT(seen[k - 1], seen[k]);
}
