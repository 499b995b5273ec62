#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "occseg/error.hpp"
#include "occseg/sim/random.hpp"
#include "occseg/sim/shapes.hpp"

using namespace occseg;
using namespace occseg::sim;

namespace {
const double kInf = std::numeric_limits<double>::infinity();
}

TEST(SimShapes, BoxEntryDistances) {
  const Shape b = make_box({0, 0, 0}, {1, 1, 1}, 1);
  EXPECT_DOUBLE_EQ(intersect(b, {-1, 0.5, 0.5}, {1, 0, 0}), 1.0);
  EXPECT_DOUBLE_EQ(intersect(b, {-1, 0.5, 0.5}, {2, 0, 0}), 0.5) << "in units of |d|";
  EXPECT_DOUBLE_EQ(intersect(b, {0.5, 0.5, 0.5}, {0, 0, 1}), 0.0) << "origin inside";
  EXPECT_EQ(intersect(b, {-1, 0.5, 0.5}, {-1, 0, 0}), kInf) << "pointing away";
  EXPECT_EQ(intersect(b, {-1, 1.5, 0.5}, {1, 0, 0}), kInf) << "passing beside";
  // Diagonal: from (-1, -1, 0.5) along (1, 1, 0) enters at the edge (0, 0).
  EXPECT_NEAR(intersect(b, {-1, -1, 0.5}, {1, 1, 0}), 1.0, 1e-12);
  EXPECT_TRUE(contains(b, {1, 1, 1}));
  EXPECT_FALSE(contains(b, {1.0001, 0.5, 0.5}));
}

TEST(SimShapes, CylinderEntryDistances) {
  const Shape c = make_cylinder(0, 0, 0, 2, 1, 1);
  EXPECT_DOUBLE_EQ(intersect(c, {-3, 0, 1}, {1, 0, 0}), 2.0);
  // Off-axis chord at y = 0.6 enters at x = -0.8.
  EXPECT_NEAR(intersect(c, {-3, 0.6, 1}, {1, 0, 0}), 2.2, 1e-12);
  EXPECT_DOUBLE_EQ(intersect(c, {0, 0, 5}, {0, 0, -1}), 3.0) << "through the top cap";
  EXPECT_EQ(intersect(c, {-3, 0, 2.5}, {1, 0, 0}), kInf) << "above it";
  EXPECT_EQ(intersect(c, {-3, 1.01, 1}, {1, 0, 0}), kInf) << "beside it";
  // From (-2, 0, 3) along (1, 0, -1)/sqrt2: meets the top cap z = 2 at x = -1 (its rim).
  const double r2 = std::sqrt(0.5);
  EXPECT_NEAR(intersect(c, {-2, 0, 3}, {r2, 0, -r2}), std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(contains(c, {0.6, 0.8, 0}));
  EXPECT_FALSE(contains(c, {0.6, 0.81, 1}));
}

TEST(SimShapes, ConeEntryDistances) {
  const Shape k = make_cone(0, 0, 0, 2, 1, 1);  // radius 1 at z = 0, apex at z = 2
  EXPECT_DOUBLE_EQ(intersect(k, {-3, 0, 1}, {1, 0, 0}), 2.5) << "radius 0.5 at mid-height";
  EXPECT_DOUBLE_EQ(intersect(k, {0, 0, 5}, {0, 0, -1}), 3.0) << "down onto the apex";
  EXPECT_DOUBLE_EQ(intersect(k, {0.9, 0, -1}, {0, 0, 1}), 1.0) << "up through the base";
  EXPECT_DOUBLE_EQ(intersect(k, {0.5, 0, 3}, {0, 0, -1}), 2.0) << "down onto the side where r = 0.5";
  // A rising ray from (-2, 0, 0) along (1, 0, 0.25) meets the side where 2 - s = 1 - s / 8:
  // s = 8/7, at x = -6/7, z = 2/7 (radius there 6/7).
  EXPECT_NEAR(intersect(k, {-2, 0, 0}, {1, 0, 0.25}), 8.0 / 7.0, 1e-12);
  // Steeper than the side: from (0.1, 0, 3) along (-0.2, 0, -1) the line starts inside the
  // upper nappe of the double cone x^2 + y^2 = (z - 2)^2 / 4, which is not part of the solid; it
  // enters the solid where 0.2 u - 0.1 = (u - 1) / 2, u = 4/3 (x = -1/6, z = 5/3).
  EXPECT_NEAR(intersect(k, {0.1, 0, 3}, {-0.2, 0, -1}), 4.0 / 3.0, 1e-12);
  EXPECT_EQ(intersect(k, {-3, 0, 2.5}, {1, 0, 0}), kInf);
  EXPECT_TRUE(contains(k, {0.5, 0, 1}));
  EXPECT_FALSE(contains(k, {0.51, 0, 1}));
}

TEST(SimShapes, EntryPointIsOnTheBoundaryForRandomRays) {
  // Independent check of all three solids: just after the entry the ray is inside, just before
  // it is not.
  const Shape shapes[3] = {make_box({-1, -0.5, 0}, {1, 0.5, 1.5}, 1), make_cylinder(0.2, -0.1, 0, 1.5, 0.8, 1),
                           make_cone(0, 0, 0, 1.5, 0.9, 1)};
  Rng rng(99);
  int hits = 0;
  for (const Shape& s : shapes)
    for (int i = 0; i < 3000; ++i) {
      const Vec3 o{4 * rng.uniform() - 2, 4 * rng.uniform() - 2, 3 * rng.uniform() - 0.75};
      if (contains(s, o)) continue;
      const Vec3 target{1.6 * rng.uniform() - 0.8, 1.6 * rng.uniform() - 0.8, 1.5 * rng.uniform()};
      Vec3 d{target[0] - o[0], target[1] - o[1], target[2] - o[2]};
      const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (double& e : d) e /= n;
      const double t = intersect(s, o, d);
      if (t == kInf) {
        EXPECT_FALSE(contains(s, target)) << "missed a solid whose point it aims at";
        continue;
      }
      ++hits;
      auto at = [&](double u) { return Vec3{o[0] + u * d[0], o[1] + u * d[1], o[2] + u * d[2]}; };
      EXPECT_FALSE(contains(s, at(t - 1e-6))) << shape_kind_name(s.kind) << " ray " << i;
      // Inside just after the entry unless the ray only grazes (then a tiny step may leave).
      if (!contains(s, at(t + 1e-6))) {
        EXPECT_TRUE(contains(s, at(t)) || contains(s, at(t + 1e-9)));
      }
    }
  EXPECT_GT(hits, 3000);
}

TEST(SimShapes, BadShapesAreRejected) {
  EXPECT_THROW(make_box({0, 0, 0}, {1, 0, 1}, 1), Error);
  EXPECT_THROW(make_cylinder(0, 0, 1, 1, 1, 1), Error);
  EXPECT_THROW(make_cone(0, 0, 0, 1, -1, 1), Error);
  EXPECT_THROW(make_box({0, 0, 0}, {1, 1, 1}, 0), Error);
}
