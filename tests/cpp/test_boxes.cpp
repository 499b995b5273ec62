// Oriented boxes of segments (occseg/boxes.hpp) on hand-built boxes, axis-aligned and rotated:
// extents and angle to within half a voxel, every voxel inside its box, metres from the map's
// frame, and the same boxes for any thread count.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "occseg/boxes.hpp"
#include "occseg/segment.hpp"
#include "synthetic.hpp"

using namespace occseg;

namespace {

constexpr double kVoxel = 0.05;
const std::array<double, 3> kOrigin{1.0, -2.0, 0.5};

// A map whose voxels with their centre inside the box (centre c, half sizes h, rotation r; voxel
// units) are occupied, the rest free.
Grid rotated_box_map(Dims d, const Eigen::Vector3d& c, const Eigen::Vector3d& h, const Eigen::Matrix3d& r) {
  Grid g(d, test::kFreeP, kVoxel);
  g.origin = kOrigin;
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x) {
        const Eigen::Vector3d q = r.transpose() * (Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5) - c);
        if (std::fabs(q.x()) <= h.x() && std::fabs(q.y()) <= h.y() && std::fabs(q.z()) <= h.z())
          g.at(x, y, z) = test::kOccP;
      }
  return g;
}

Result segmented(const Grid& g, int threads = 1) {
  Params p = Params::defaults();
  p.threads = threads;
  return segment(g, p);
}

// The one occupied segment's index.
std::size_t occupied(const Result& r) {
  std::size_t found = r.segments.size(), count = 0;
  for (std::size_t i = 0; i < r.segments.size(); ++i)
    if (r.segments[i].state == State::occupied) {
      found = i;
      ++count;
    }
  EXPECT_EQ(count, 1u);
  return found;
}

Eigen::Matrix3d rotation_of(const OrientedBox& b) {
  return Eigen::Quaterniond(b.quaternion[0], b.quaternion[1], b.quaternion[2], b.quaternion[3]).toRotationMatrix();
}

// Every corner of every voxel of segment `id` lies in the box (metres, a hair of rounding).
void expect_voxels_inside(const Result& r, std::uint32_t id, const OrientedBox& b) {
  const Eigen::Matrix3d rot = rotation_of(b);
  const Eigen::Vector3d c(b.center[0], b.center[1], b.center[2]);
  std::size_t i = 0, outside = 0;
  for (std::size_t z = 0; z < r.dims.nz; ++z)
    for (std::size_t y = 0; y < r.dims.ny; ++y)
      for (std::size_t x = 0; x < r.dims.nx; ++x, ++i) {
        if (r.labels[i] != id) continue;
        for (int corner = 0; corner < 8; ++corner) {
          const Eigen::Vector3d w(kOrigin[0] + (double(x) + (corner & 1)) * kVoxel,
                                  kOrigin[1] + (double(y) + ((corner >> 1) & 1)) * kVoxel,
                                  kOrigin[2] + (double(z) + ((corner >> 2) & 1)) * kVoxel);
          const Eigen::Vector3d q = rot.transpose() * (w - c);
          for (int k = 0; k < 3; ++k)
            if (std::fabs(q[k]) > b.extents[k] / 2 + 1e-9) ++outside;
        }
      }
  EXPECT_EQ(outside, 0u);
}

// Extents of the smallest box along `axes` (voxel units) holding the segment's voxel cubes: what
// a perfect fit in the true orientation gives.
Eigen::Vector3d extents_along(const Result& r, std::uint32_t id, const Eigen::Matrix3d& axes) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
  std::size_t i = 0;
  for (std::size_t z = 0; z < r.dims.nz; ++z)
    for (std::size_t y = 0; y < r.dims.ny; ++y)
      for (std::size_t x = 0; x < r.dims.nx; ++x, ++i)
        if (r.labels[i] == id) {
          const Eigen::Vector3d t = axes.transpose() * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
          lo = lo.cwiseMin(t);
          hi = hi.cwiseMax(t);
        }
  Eigen::Vector3d e;
  for (int k = 0; k < 3; ++k) e[k] = hi[k] - lo[k] + axes.col(k).cwiseAbs().sum();
  return e;
}

}  // namespace

TEST(OrientedBoxes, AxisAlignedBoxIsItsVoxelBoxWithIdentityRotation) {
  Grid g(Dims{24, 20, 16}, test::kFreeP, kVoxel);
  g.origin = kOrigin;
  test::box(g, 3, 5, 2, 13, 11, 6, test::kOccP);  // 10 x 6 x 4 voxels
  const Result r = segmented(g);
  const std::size_t s = occupied(r);
  const OrientedBox b = oriented_boxes(r, g.voxel_size, g.origin)[s];
  EXPECT_EQ(b.quaternion, (std::array<double, 4>{1, 0, 0, 0}));
  EXPECT_NEAR(b.extents[0], 10 * kVoxel, 1e-12);
  EXPECT_NEAR(b.extents[1], 6 * kVoxel, 1e-12);
  EXPECT_NEAR(b.extents[2], 4 * kVoxel, 1e-12);
  EXPECT_NEAR(b.center[0], kOrigin[0] + 8 * kVoxel, 1e-12);
  EXPECT_NEAR(b.center[1], kOrigin[1] + 8 * kVoxel, 1e-12);
  EXPECT_NEAR(b.center[2], kOrigin[2] + 4 * kVoxel, 1e-12);
  // Free space gets its axis-aligned voxel box: the whole map here.
  const OrientedBox f = oriented_boxes(r, g.voxel_size, g.origin)[r.labels[0]];
  EXPECT_EQ(f.quaternion, (std::array<double, 4>{1, 0, 0, 0}));
  EXPECT_NEAR(f.extents[0], 24 * kVoxel, 1e-12);
  EXPECT_NEAR(f.center[2], kOrigin[2] + 8 * kVoxel, 1e-12);
}

TEST(OrientedBoxes, BoxTurnedAboutZ) {
  for (const double degrees : {30.0, -20.0, 12.0}) {
    SCOPED_TRACE(degrees);
    const double a = degrees * M_PI / 180;
    const Eigen::Matrix3d rot = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d half(11, 4.5, 3);  // a 22 x 9 x 6 voxel box
    const Grid g = rotated_box_map(Dims{40, 40, 16}, Eigen::Vector3d(20.3, 19.6, 8.2), half, rot);
    const Result r = segmented(g);
    const std::size_t s = occupied(r);
    const OrientedBox b = oriented_boxes(r, g.voxel_size, g.origin)[s];
    expect_voxels_inside(r, static_cast<std::uint32_t>(s), b);
    // The long axis: its angle about z (the box is the same every 180 degrees) within half a
    // voxel at its ends, i.e. atan(0.5 / 11).
    const Eigen::Matrix3d fit = rotation_of(b);
    int longest = 0;
    for (int k = 1; k < 3; ++k)
      if (b.extents[k] > b.extents[longest]) longest = k;
    const Eigen::Vector3d u = fit.col(longest);
    EXPECT_NEAR(u.z(), 0.0, 1e-9);
    double err = std::atan2(u.y(), u.x()) - a;
    err -= M_PI * std::round(err / M_PI);
    EXPECT_LE(std::fabs(err), std::atan(0.5 / half.x()));
    // Extents within half a voxel of the voxels' box in the true orientation, and never less
    // than the true box less half a voxel.
    const Eigen::Vector3d want = extents_along(r, static_cast<std::uint32_t>(s), rot);
    std::array<double, 3> got = b.extents, wanted{want[0], want[1], want[2]}, truth{22, 9, 6};
    std::sort(got.begin(), got.end());
    std::sort(wanted.begin(), wanted.end());
    std::sort(truth.begin(), truth.end());
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(got[k] / kVoxel, wanted[k], 0.5) << k;
      EXPECT_GE(got[k] / kVoxel, truth[k] - 0.5) << k;
    }
  }
}

TEST(OrientedBoxes, TiltedLongBoxFollowsItsPrincipalAxes) {
  const Eigen::Matrix3d rot = (Eigen::AngleAxisd(0.45, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(-0.35, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
  const Eigen::Vector3d half(14, 4, 2.5);  // 28 x 8 x 5 voxels
  const Grid g = rotated_box_map(Dims{44, 40, 32}, Eigen::Vector3d(22.1, 20.4, 16.3), half, rot);
  const Result r = segmented(g);
  const std::size_t s = occupied(r);
  const OrientedBox b = oriented_boxes(r, g.voxel_size, g.origin)[s];
  expect_voxels_inside(r, static_cast<std::uint32_t>(s), b);
  const Eigen::Matrix3d fit = rotation_of(b);
  // The first axis is the longest (largest variance): parallel to the true long axis to within
  // half a voxel at its ends.
  const double cosine = std::fabs(fit.col(0).dot(rot.col(0)));
  EXPECT_LE(std::acos(std::min(1.0, cosine)), std::atan(0.5 / half.x()));
  const Eigen::Vector3d want = extents_along(r, static_cast<std::uint32_t>(s), rot);
  EXPECT_NEAR(b.extents[0] / kVoxel, want[0], 0.5);
  EXPECT_NEAR(b.extents[1] / kVoxel, want[1], 0.5);
  EXPECT_NEAR(b.extents[2] / kVoxel, want[2], 0.5);
}

TEST(OrientedBoxes, SameForAnyThreadCount) {
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Grid g = rotated_box_map(Dims{48, 40, 32}, Eigen::Vector3d(16, 20, 15), Eigen::Vector3d(9, 5, 3), rot);
  test::box(g, 36, 4, 4, 44, 30, 9, test::kOccP);  // a second object
  const Result one = segmented(g, 1), two = segmented(g, 2), all = segmented(g, 0);
  const auto b1 = oriented_boxes(one, g.voxel_size, g.origin);
  for (const Result* r : {&two, &all}) {
    const auto b = oriented_boxes(*r, g.voxel_size, g.origin);
    ASSERT_EQ(b.size(), b1.size());
    for (std::size_t i = 0; i < b.size(); ++i) {
      EXPECT_EQ(b[i].center, b1[i].center);
      EXPECT_EQ(b[i].extents, b1[i].extents);
      EXPECT_EQ(b[i].quaternion, b1[i].quaternion);
    }
  }
}
