#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/geometry.hpp"
#include "occseg/parallel.hpp"
#include "occseg/scan_options.hpp"

namespace occseg {

void ScanOptions::validate() const {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw Error(Status::invalid_argument, "voxel size " + std::to_string(voxel_size) + " is not a positive number");
  if (!(margin >= 0) || !std::isfinite(margin))
    throw Error(Status::invalid_argument, "margin " + std::to_string(margin) + " is not a non-negative number");
  if (threads < 0) throw Error(Status::invalid_argument, "threads " + std::to_string(threads) + " is negative");
  model.validate();
  if (bbox) frame_for_box(*bbox, voxel_size);
  if (sensor_pose && !sensor_pose->matrix().allFinite())
    throw Error(Status::bad_value, "sensor pose is not finite");
  if (sensor_origin || sensor_orientation)  // make_pose names a non-finite value or a zero quaternion
    make_pose(sensor_origin.value_or(Vec3{0, 0, 0}), sensor_orientation.value_or(std::array<double, 4>{1, 0, 0, 0}));
}

Eigen::Isometry3d ScanOptions::pose_for(const Eigen::Isometry3d& stored) const {
  if (sensor_pose) return *sensor_pose;
  if (!sensor_origin && !sensor_orientation) return stored;
  Eigen::Isometry3d pose = stored;
  if (sensor_orientation) pose.linear() = make_pose({0, 0, 0}, *sensor_orientation).linear();
  if (sensor_origin) pose.translation() = Eigen::Vector3d((*sensor_origin)[0], (*sensor_origin)[1], (*sensor_origin)[2]);
  return pose;
}

GridFrame frame_for_box(const Box& box, double voxel_size) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw Error(Status::bad_value, "voxel size " + std::to_string(voxel_size) + " is not positive");
  GridFrame f;
  f.voxel_size = voxel_size;
  std::size_t n[3];
  for (int k = 0; k < 3; ++k) {
    const double lo = box.min[k], hi = box.max[k];
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
      throw Error(Status::bad_value, "bounding box axis " + std::string(1, "xyz"[k]) + " [" + std::to_string(lo) +
                                         ", " + std::to_string(hi) + "] is empty or not finite");
    // A box that is a whole number of voxels (up to rounding) gets exactly that many.
    const double cells = std::ceil((hi - lo) / voxel_size - 1e-9);
    if (!(cells <= double(kMaxVoxels)))
      throw Error(Status::bad_dims, "bounding box needs too many voxels of " + std::to_string(voxel_size) + " m");
    n[k] = std::max<std::size_t>(1, static_cast<std::size_t>(cells));
    f.origin[k] = lo;
  }
  f.dims = Dims{n[0], n[1], n[2]};
  check_dims(f.dims);
  check_geometry(f.dims, f.voxel_size, f.origin);
  return f;
}

void ScanBounds::extend(const Vec3& p) {
  if (!any_) {
    lo_ = hi_ = p;
    any_ = true;
    return;
  }
  for (int k = 0; k < 3; ++k) {
    lo_[k] = std::min(lo_[k], p[k]);
    hi_[k] = std::max(hi_[k], p[k]);
  }
}

template <class T>
void ScanBounds::add_points(const Eigen::Isometry3d& pose, const T* xyz, std::size_t count, std::size_t stride,
                            double max_range) {
  const Eigen::Vector3d s = pose.translation();
  if (!s.allFinite()) throw Error(Status::bad_value, "sensor origin is not finite");
  extend({s.x(), s.y(), s.z()});
  const Eigen::Matrix3d r = pose.linear();
  for (std::size_t i = 0; i < count; ++i) {
    const T* p = xyz + i * stride;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    Eigen::Vector3d w = r * Eigen::Vector3d(p[0], p[1], p[2]) + s;
    if (max_range >= 0) {
      const Eigen::Vector3d d = w - s;
      const double len = d.norm();
      if (len > max_range) w = s + d * (max_range / len);
    }
    extend({w.x(), w.y(), w.z()});
  }
}

void ScanBounds::add(const Eigen::Isometry3d& pose, const float* xyz, std::size_t count, std::size_t stride,
                     double max_range) {
  add_points(pose, xyz, count, stride, max_range);
}

void ScanBounds::add(const Eigen::Isometry3d& pose, const double* xyz, std::size_t count, std::size_t stride,
                     double max_range) {
  add_points(pose, xyz, count, stride, max_range);
}

GridFrame ScanBounds::frame(double voxel_size, double margin) const {
  if (!any_) throw Error(Status::bad_value, "no scan to fit a grid to");
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw Error(Status::bad_value, "voxel size " + std::to_string(voxel_size) + " is not positive");
  // Before fitting: far out, floor(x / voxel_size) + 1 rounds back to floor(x / voxel_size) and
  // the box would have no voxel at all, or points would share voxels they do not share.
  for (int k = 0; k < 3; ++k) {
    check_coordinate(lo_[k], k, voxel_size, "points or sensor origins");
    check_coordinate(hi_[k], k, voxel_size, "points or sensor origins");
  }
  const GridFrame f = fit_frame({lo_, hi_}, voxel_size, margin);
  check_geometry(f.dims, f.voxel_size, f.origin);
  return f;
}

void attach_progress(OccupancyFusion& fusion, const ScanOptions& options, const std::size_t* before,
                     std::size_t total) {
  if (!options.progress || total == 0) return;
  fusion.set_progress([&options, before, total](std::size_t done, std::size_t) {
    return options.progress(std::min(1.0, double(*before + done) / double(total)));
  });
}

bool is_identity(const Eigen::Isometry3f& pose) {
  return pose.matrix() == Eigen::Matrix4f::Identity();
}

bool is_identity(const Eigen::Isometry3d& pose) {
  return pose.matrix() == Eigen::Matrix4d::Identity();
}

void insert_points(OccupancyFusion& fusion, const Eigen::Isometry3f& pose, const float* xyz, std::size_t count,
                   std::size_t stride, int threads) {
  const Eigen::Vector3f s = pose.translation();
  const Vec3 sensor{s.x(), s.y(), s.z()};
  if (is_identity(pose)) {
    fusion.insert_scan(sensor, xyz, count, stride, threads);
    return;
  }
  // The fusion takes world coordinates: transform into a packed copy (NaNs stay NaN).
  std::vector<float> world(3 * count);
  const Eigen::Matrix3f r = pose.linear();
  parallel_for(count, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const float* p = xyz + i * stride;
      const Eigen::Vector3f w = r * Eigen::Vector3f(p[0], p[1], p[2]) + s;
      world[3 * i] = w.x();
      world[3 * i + 1] = w.y();
      world[3 * i + 2] = w.z();
    }
  });
  fusion.insert_scan(sensor, world.data(), count, 3, threads);
}

namespace {

const GridFrame& checked(const GridFrame& f) {
  check_geometry(f.dims, f.voxel_size, f.origin);
  return f;
}

GridFrame at_zero(GridFrame f) {
  f.origin = {0, 0, 0};
  return f;
}

}  // namespace

ScanFusion::ScanFusion(const GridFrame& frame, const SensorModel& model)
    : frame_(checked(frame)), fusion_(at_zero(frame), model) {}

namespace {

// The points of a scan relative to the frame's corner, as floats: the sensor-frame points moved
// by the pose in double (the translation taken relative to the corner first), so only the small
// differences are rounded to float. NaN points stay NaN. The one conversion ScanFusion::insert
// and scan_point_voxels share, so a point's voxel is the voxel its return went into.
template <class T>
std::vector<float> relative_points(const Eigen::Matrix3d& r, const Eigen::Vector3d& s, const T* xyz,
                                   std::size_t count, std::size_t stride, int threads) {
  std::vector<float> rel(3 * count);
  parallel_for(count, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const T* p = xyz + i * stride;
      const Eigen::Vector3d w = r * Eigen::Vector3d(p[0], p[1], p[2]) + s;
      rel[3 * i] = static_cast<float>(w.x());
      rel[3 * i + 1] = static_cast<float>(w.y());
      rel[3 * i + 2] = static_cast<float>(w.z());
    }
  });
  return rel;
}

// The sensor relative to the corner of a frame, after the range check of ScanFusion::insert.
Eigen::Vector3d relative_sensor(const GridFrame& frame, const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d t = pose.translation();
  for (int k = 0; k < 3; ++k) check_coordinate(t[k], k, frame.voxel_size, "sensor origin");
  return t - Eigen::Vector3d(frame.origin[0], frame.origin[1], frame.origin[2]);
}

}  // namespace

void ScanFusion::insert(const Eigen::Isometry3d& pose, const float* xyz, std::size_t count, std::size_t stride,
                        int threads) {
  const Eigen::Vector3d s = relative_sensor(frame_, pose);
  const Vec3 sensor{s.x(), s.y(), s.z()};
  const bool at_origin = frame_.origin[0] == 0 && frame_.origin[1] == 0 && frame_.origin[2] == 0;
  if (is_identity(pose) && at_origin) {  // relative = world: the points as they are, no copy
    fusion_.insert_scan(sensor, xyz, count, stride, threads);
    return;
  }
  const std::vector<float> rel = relative_points(pose.linear(), s, xyz, count, stride, threads);
  fusion_.insert_scan(sensor, rel.data(), count, 3, threads);
}

void ScanFusion::insert(const Eigen::Isometry3d& pose, const double* xyz, std::size_t count, std::size_t stride,
                        int threads) {
  // Always through the copy: the fusion takes floats. With the identity pose the copy holds
  // exactly float(x), float(y), float(z), as the float path would read them.
  const Eigen::Vector3d s = relative_sensor(frame_, pose);
  const std::vector<float> rel = relative_points(pose.linear(), s, xyz, count, stride, threads);
  fusion_.insert_scan({s.x(), s.y(), s.z()}, rel.data(), count, 3, threads);
}

template <class T>
void scan_point_voxels(const GridFrame& frame, const Eigen::Isometry3d& pose, const T* xyz, std::size_t count,
                       std::size_t stride, std::uint32_t* out, const std::function<std::uint32_t(std::uint64_t)>& label,
                       int threads) {
  const Eigen::Vector3d s = relative_sensor(frame, pose);
  GridFrame zero = frame;
  zero.origin = {0, 0, 0};
  const Vec3 sensor{s.x(), s.y(), s.z()};
  // In blocks, so a cloud of any size needs only a block's floats at a time.
  constexpr std::size_t kBlock = std::size_t(1) << 16;
  for (std::size_t b = 0; b < count; b += kBlock) {
    const std::size_t n = std::min(kBlock, count - b);
    const std::vector<float> rel = relative_points(pose.linear(), s, xyz + b * stride, n, stride, threads);
    parallel_for(n, threads, [&](std::size_t i0, std::size_t i1) {
      for (std::size_t i = i0; i < i1; ++i) {
        std::uint64_t v;
        out[b + i] = endpoint_voxel(zero, sensor, &rel[3 * i], v) ? label(v) : kNoPointLabel;
      }
    });
  }
}

template void scan_point_voxels<float>(const GridFrame&, const Eigen::Isometry3d&, const float*, std::size_t,
                                       std::size_t, std::uint32_t*, const std::function<std::uint32_t(std::uint64_t)>&,
                                       int);
template void scan_point_voxels<double>(const GridFrame&, const Eigen::Isometry3d&, const double*, std::size_t,
                                        std::size_t, std::uint32_t*,
                                        const std::function<std::uint32_t(std::uint64_t)>&, int);

Grid ScanFusion::grid() const {
  Grid g = fusion_.grid();
  g.origin = frame_.origin;
  return g;
}

Eigen::Isometry3d make_pose(const Vec3& origin, const std::array<double, 4>& q) {
  for (double v : origin)
    if (!std::isfinite(v)) throw Error(Status::bad_value, "sensor origin is not finite");
  double m = 0;
  for (double v : q) {
    if (!std::isfinite(v)) throw Error(Status::bad_value, "sensor orientation is not finite");
    m = std::max(m, std::fabs(v));
  }
  if (m == 0) throw Error(Status::bad_value, "sensor orientation quaternion is zero");
  // Scaled by a power of two to bring the largest component into [1, 2): the squares can then
  // neither overflow (1e200) nor underflow (1e-200). The scaling is exact (bar components too
  // small to matter), so where the unscaled arithmetic does not overflow it gives the same bits.
  const int e = std::ilogb(m);
  Eigen::Quaterniond qd(std::ldexp(q[0], -e), std::ldexp(q[1], -e), std::ldexp(q[2], -e), std::ldexp(q[3], -e));
  qd.normalize();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = qd.toRotationMatrix();
  pose.translation() = Eigen::Vector3d(origin[0], origin[1], origin[2]);
  return pose;
}

}  // namespace occseg
