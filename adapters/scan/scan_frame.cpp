#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "occseg/error.hpp"
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

void ScanBounds::add(const Eigen::Isometry3f& pose, const float* xyz, std::size_t count, std::size_t stride,
                     double max_range) {
  const Eigen::Vector3f s = pose.translation();
  if (!s.allFinite()) throw Error(Status::bad_value, "sensor origin is not finite");
  extend({s.x(), s.y(), s.z()});
  const Eigen::Matrix3f r = pose.linear();
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = xyz + i * stride;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    Eigen::Vector3d w = (r * Eigen::Vector3f(p[0], p[1], p[2]) + s).cast<double>();
    if (max_range >= 0) {
      const Eigen::Vector3d d = w - s.cast<double>();
      const double len = d.norm();
      if (len > max_range) w = s.cast<double>() + d * (max_range / len);
    }
    extend({w.x(), w.y(), w.z()});
  }
}

GridFrame ScanBounds::frame(double voxel_size, double margin) const {
  if (!any_) throw Error(Status::bad_value, "no scan to fit a grid to");
  return fit_frame({lo_, hi_}, voxel_size, margin);
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

Eigen::Isometry3f make_pose(const Vec3& origin, const std::array<double, 4>& q) {
  // The pose is held in floats: converting a finite double beyond their range is undefined.
  for (double v : origin)
    if (!std::isfinite(v) || std::fabs(v) > double(std::numeric_limits<float>::max()))
      throw Error(Status::bad_value, "sensor origin is not finite in single precision");
  double n2 = 0;
  for (double v : q) {
    if (!std::isfinite(v)) throw Error(Status::bad_value, "sensor orientation is not finite");
    n2 += v * v;
  }
  if (!(n2 > 1e-12)) throw Error(Status::bad_value, "sensor orientation quaternion is zero");
  Eigen::Quaterniond qd(q[0], q[1], q[2], q[3]);
  qd.normalize();
  Eigen::Isometry3f pose = Eigen::Isometry3f::Identity();
  pose.linear() = qd.toRotationMatrix().cast<float>();
  pose.translation() = Eigen::Vector3f(float(origin[0]), float(origin[1]), float(origin[2]));
  return pose;
}

}  // namespace occseg
