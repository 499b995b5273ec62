// Oriented bounding boxes of segments (boxes.hpp). All geometry is done in voxel units with the
// voxel (i, j, k) centred at (i + 0.5, j + 0.5, k + 0.5); metres only at the end.
#include "occseg/boxes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace occseg {

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

struct Point {
  std::int64_t x, y, z;  // one axis of a map may have up to 2^40 voxels
};

// A candidate box: rotation columns = box axes, bounds of the voxel cubes along each axis.
struct Fit {
  Mat3 axes = Mat3::Identity();
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  double volume() const { return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
};

// The smallest box along `axes` holding every voxel cube whole: a unit cube projects onto a unit
// axis a as an interval of width |ax| + |ay| + |az| around its centre's projection.
Fit fit_along(const Mat3& axes, const std::vector<Point>& pts, std::size_t begin, std::size_t end) {
  Fit f;
  f.axes = axes;
  for (int k = 0; k < 3; ++k) {
    const Vec3 a = axes.col(k);
    double mn = HUGE_VAL, mx = -HUGE_VAL;
    for (std::size_t i = begin; i < end; ++i) {
      const double t = a.x() * (pts[i].x + 0.5) + a.y() * (pts[i].y + 0.5) + a.z() * (pts[i].z + 0.5);
      mn = std::min(mn, t);
      mx = std::max(mx, t);
    }
    const double half = 0.5 * (std::fabs(a.x()) + std::fabs(a.y()) + std::fabs(a.z()));
    f.lo[k] = mn - half;
    f.hi[k] = mx + half;
  }
  return f;
}

// Makes a rotation of three unit axes deterministic and proper: each axis points where its
// largest component (the first on ties) is positive, and the third is the cross product of the
// first two (a right-handed frame, a rotation and not a reflection).
Mat3 canonical(Mat3 m) {
  for (int k = 0; k < 2; ++k) {
    int big = 0;
    for (int j = 1; j < 3; ++j)
      if (std::fabs(m(j, k)) > std::fabs(m(big, k)) + 1e-12) big = j;
    if (m(big, k) < 0) m.col(k) = -m.col(k);
  }
  m.col(2) = m.col(0).cross(m.col(1)).normalized();
  return m;
}

// Principal axes of the points, largest variance first. The sums are exact integers (128-bit,
// of the offsets from the segment's first voxel: |offset| < 2^41, so n * offset^2 < 2^122 never
// overflows), so they do not depend on the order of the points; the covariance is then formed
// from them in long double.
Mat3 principal_axes(const std::vector<Point>& pts, std::size_t begin, std::size_t end) {
  __int128 s[3] = {0, 0, 0}, ss[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  const Point& o = pts[begin];
  for (std::size_t i = begin; i < end; ++i) {
    const std::int64_t v[3] = {pts[i].x - o.x, pts[i].y - o.y, pts[i].z - o.z};
    for (int a = 0; a < 3; ++a) {
      s[a] += v[a];
      for (int b = a; b < 3; ++b) ss[a][b] += __int128(v[a]) * v[b];
    }
  }
  const long double n = static_cast<long double>(end - begin);
  long double mean[3];
  for (int a = 0; a < 3; ++a) mean[a] = static_cast<long double>(s[a]) / n;
  Mat3 c;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b)
      c(a, b) = c(b, a) = static_cast<double>(static_cast<long double>(ss[a][b]) / n - mean[a] * mean[b]);
  Eigen::SelfAdjointEigenSolver<Mat3> eig(c);
  Mat3 v = eig.eigenvectors();  // ascending eigenvalues: reverse to largest first
  Mat3 m;
  m.col(0) = v.col(2);
  m.col(1) = v.col(1);
  m.col(2) = v.col(0);
  return canonical(m);
}

__int128 cross(const Point& o, const Point& a, const Point& b) {
  return __int128(a.x - o.x) * (b.y - o.y) - __int128(a.y - o.y) * (b.x - o.x);
}

// The rotation about z whose (x, y) rectangle holding the voxels has the least area, among the
// directions of the edges of the convex hull of the voxel centres' (x, y) (a minimum-area
// enclosing rectangle has a side along a hull edge). The angle is brought into [-45, 45)
// degrees, where the rectangle is the same. Identity when the hull has fewer than 3 points.
Mat3 best_yaw(const std::vector<Point>& pts, std::size_t begin, std::size_t end) {
  // Only the first and the last voxel of each row y can be a corner of the hull (any other lies
  // between them), so the hull is that of those two per row: the same corners in the same
  // order, from a sort of two points per row instead of one per voxel.
  std::int64_t y0 = pts[begin].y, y1 = pts[begin].y;
  for (std::size_t i = begin; i < end; ++i) y0 = std::min(y0, pts[i].y), y1 = std::max(y1, pts[i].y);
  std::vector<std::int64_t> row_lo(std::size_t(y1 - y0 + 1), INT64_MAX), row_hi(row_lo.size(), INT64_MIN);
  for (std::size_t i = begin; i < end; ++i) {
    const std::size_t r = std::size_t(pts[i].y - y0);
    row_lo[r] = std::min(row_lo[r], pts[i].x);
    row_hi[r] = std::max(row_hi[r], pts[i].x);
  }
  std::vector<Point> xy;
  xy.reserve(2 * row_lo.size());
  for (std::size_t r = 0; r < row_lo.size(); ++r)
    if (row_lo[r] <= row_hi[r]) {
      xy.push_back({row_lo[r], y0 + std::int64_t(r), 0});
      if (row_hi[r] != row_lo[r]) xy.push_back({row_hi[r], y0 + std::int64_t(r), 0});
    }
  std::sort(xy.begin(), xy.end(), [](const Point& a, const Point& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  xy.erase(std::unique(xy.begin(), xy.end(), [](const Point& a, const Point& b) { return a.x == b.x && a.y == b.y; }),
           xy.end());
  if (xy.size() < 3) return Mat3::Identity();
  // Andrew's monotone chain, exact in integers.
  std::vector<Point> hull(2 * xy.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < xy.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], xy[i]) <= 0) --k;
    hull[k++] = xy[i];
  }
  for (std::size_t i = xy.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], xy[i]) <= 0) --k;
    hull[k++] = xy[i];
  }
  hull.resize(k - 1);
  if (hull.size() < 3) return Mat3::Identity();
  double best_area = HUGE_VAL, best_angle = 0;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Point& a = hull[i];
    const Point& b = hull[(i + 1) % hull.size()];
    double angle = std::atan2(double(b.y - a.y), double(b.x - a.x));
    angle -= (M_PI / 2) * std::floor((angle + M_PI / 4) / (M_PI / 2));  // into [-45, 45) degrees
    const double c = std::cos(angle), s = std::sin(angle);
    double u0 = HUGE_VAL, u1 = -HUGE_VAL, v0 = HUGE_VAL, v1 = -HUGE_VAL;
    for (const Point& p : hull) {
      const double u = c * p.x + s * p.y, v = -s * p.x + c * p.y;
      u0 = std::min(u0, u);
      u1 = std::max(u1, u);
      v0 = std::min(v0, v);
      v1 = std::max(v1, v);
    }
    const double w = std::fabs(c) + std::fabs(s);  // a voxel's width along either side
    const double area = (u1 - u0 + w) * (v1 - v0 + w);
    if (area < best_area * (1 - 1e-12)) {
      best_area = area;
      best_angle = angle;
    }
  }
  const double c = std::cos(best_angle), s = std::sin(best_angle);
  Mat3 m;
  m << c, -s, 0, s, c, 0, 0, 0, 1;
  return m;
}

OrientedBox to_metres(const Fit& f, double voxel_size, const std::array<double, 3>& origin) {
  OrientedBox b;
  Vec3 mid(0, 0, 0);
  for (int k = 0; k < 3; ++k) {
    mid += f.axes.col(k) * (0.5 * (f.lo[k] + f.hi[k]));
    b.extents[k] = (f.hi[k] - f.lo[k]) * voxel_size;
  }
  for (int k = 0; k < 3; ++k) b.center[k] = origin[k] + mid[k] * voxel_size;
  Eigen::Quaterniond q(f.axes);
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  b.quaternion = {q.w(), q.x(), q.y(), q.z()};
  return b;
}

}  // namespace

std::vector<OrientedBox> oriented_boxes(const Result& r, double voxel_size, const std::array<double, 3>& origin) {
  const std::size_t n = r.segments.size();
  std::vector<OrientedBox> boxes(n);
  // The voxels of the occupied segments, grouped by segment (a counting sort), x fastest.
  std::vector<std::size_t> start(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    start[i + 1] = start[i] + (r.segments[i].state == State::occupied ? r.segments[i].voxels : 0);
  std::vector<Point> pts(start[n]);
  if (!pts.empty()) {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    const Dims& d = r.dims;
    std::size_t i = 0;
    for (std::size_t z = 0; z < d.nz; ++z)
      for (std::size_t y = 0; y < d.ny; ++y)
        for (std::size_t x = 0; x < d.nx; ++x, ++i) {
          const std::uint32_t l = r.labels[i];
          if (l < n && r.segments[l].state == State::occupied && fill[l] < start[l + 1])
            pts[fill[l]++] = {std::int64_t(x), std::int64_t(y), std::int64_t(z)};
        }
  }
  for (std::size_t s = 0; s < n; ++s) {
    const Segment& seg = r.segments[s];
    Fit aligned;
    for (int k = 0; k < 3; ++k) {
      aligned.lo[k] = seg.bbox_min[k];
      aligned.hi[k] = double(seg.bbox_max[k]) + 1.0;
    }
    Fit best = aligned;
    const std::size_t b = start[s], e = start[s + 1];
    if (seg.state == State::occupied && e - b >= 2) {
      best = fit_along(Mat3::Identity(), pts, b, e);
      for (const Mat3& axes : {principal_axes(pts, b, e), best_yaw(pts, b, e)}) {
        const Fit f = fit_along(axes, pts, b, e);
        if (f.volume() < best.volume() * (1 - 1e-9)) best = f;
      }
    }
    boxes[s] = to_metres(best, voxel_size, origin);
  }
  return boxes;
}

}  // namespace occseg
