// PCL point clouds in and out (liboccseg_pcl). Includes PCL headers: include it only where PCL
// types are used; occseg/pcd.hpp is the PCL-free interface to the same library.
//
// Any point type with float x, y, z members works. The templates are thin: they hand the cloud's
// memory to the core fusion without copying (x, y, z are read in place with the point's stride),
// and are instantiated once in the library for the common PCL point types (see the extern
// template list at the end).
#pragma once
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <memory>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/fusion.hpp"
#include "occseg/pcd.hpp"
#include "occseg/scan_options.hpp"
#include "occseg/segment.hpp"

namespace occseg {

namespace detail {
// Where x, y, z of a point type sit, in floats: x at `offset`, y and z right after, and points
// `stride` floats apart. packed == false when the layout does not allow reading in place.
struct XyzLayout {
  std::size_t offset = 0, stride = 0;
  bool packed = false;
};
template <typename PointT>
XyzLayout xyz_layout() {
  const PointT p{};
  const char* base = reinterpret_cast<const char*>(&p);
  const std::ptrdiff_t ox = reinterpret_cast<const char*>(&p.x) - base;
  const std::ptrdiff_t oy = reinterpret_cast<const char*>(&p.y) - base;
  const std::ptrdiff_t oz = reinterpret_cast<const char*>(&p.z) - base;
  XyzLayout l;
  l.packed = sizeof(p.x) == sizeof(float) && sizeof(PointT) % sizeof(float) == 0 && ox % sizeof(float) == 0 &&
             oy == ox + std::ptrdiff_t(sizeof(float)) && oz == ox + 2 * std::ptrdiff_t(sizeof(float));
  l.offset = static_cast<std::size_t>(ox) / sizeof(float);
  l.stride = sizeof(PointT) / sizeof(float);
  return l;
}
// Calls fn(xyz, count, stride) with the cloud's coordinates as floats, in place when possible.
template <typename PointT, typename Fn>
void with_xyz(const pcl::PointCloud<PointT>& cloud, Fn&& fn) {
  if (cloud.points.empty()) return fn(static_cast<const float*>(nullptr), std::size_t(0), std::size_t(3));
  const XyzLayout l = xyz_layout<PointT>();
  if (l.packed)
    return fn(reinterpret_cast<const float*>(cloud.points.data()) + l.offset, cloud.points.size(), l.stride);
  std::vector<float> xyz(3 * cloud.points.size());
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    xyz[3 * i] = cloud.points[i].x;
    xyz[3 * i + 1] = cloud.points[i].y;
    xyz[3 * i + 2] = cloud.points[i].z;
  }
  fn(static_cast<const float*>(xyz.data()), cloud.points.size(), std::size_t(3));
}
}  // namespace detail

// The sensor pose stored with a cloud (sensor_origin_, sensor_orientation_): maps the cloud's
// points into the world frame, with the sensor at its translation. The quaternion is normalised
// as make_pose does (no overflow to a silent identity); Error(bad_value) for a zero or
// non-finite one. cloud_pose_d is the same in double, as the fusion uses it.
template <typename PointT>
Eigen::Isometry3d cloud_pose_d(const pcl::PointCloud<PointT>& cloud) {
  const Eigen::Vector4f& o = cloud.sensor_origin_;
  const Eigen::Quaternionf& q = cloud.sensor_orientation_;
  return make_pose({o.x(), o.y(), o.z()}, {q.w(), q.x(), q.y(), q.z()});
}
template <typename PointT>
Eigen::Isometry3f cloud_pose(const pcl::PointCloud<PointT>& cloud) {
  return Eigen::Isometry3f(cloud_pose_d(cloud).template cast<float>());
}

// Ray-casts one cloud into `fusion`: points are in the sensor frame, `pose` maps them to the
// world and the sensor sits at pose.translation(). NaN points are skipped; returns beyond the
// fusion's max range mark free space only. World coordinates in float (insert_points): for
// maps far from the world origin use integrate_clouds, which keeps its precision.
template <typename PointT>
void insert_cloud(OccupancyFusion& fusion, const pcl::PointCloud<PointT>& cloud, const Eigen::Isometry3f& pose,
                  int threads = 0) {
  detail::with_xyz(cloud, [&](const float* xyz, std::size_t n, std::size_t stride) {
    insert_points(fusion, pose, xyz, n, stride, threads);
  });
}

// Same, with the cloud's own sensor pose (cloud_pose).
template <typename PointT>
void insert_cloud(OccupancyFusion& fusion, const pcl::PointCloud<PointT>& cloud, int threads = 0) {
  insert_cloud(fusion, cloud, cloud_pose(cloud), threads);
}

// Extends `bounds` by a cloud seen from `pose` (for fitting a grid before fusing).
template <typename PointT>
void add_cloud_bounds(ScanBounds& bounds, const pcl::PointCloud<PointT>& cloud, const Eigen::Isometry3d& pose,
                      double max_range) {
  detail::with_xyz(cloud, [&](const float* xyz, std::size_t n, std::size_t stride) {
    bounds.add(pose, xyz, n, stride, max_range);
  });
}
template <typename PointT>
void add_cloud_bounds(ScanBounds& bounds, const pcl::PointCloud<PointT>& cloud, const Eigen::Isometry3f& pose,
                      double max_range) {
  detail::with_xyz(cloud, [&](const float* xyz, std::size_t n, std::size_t stride) {
    bounds.add(pose, xyz, n, stride, max_range);
  });
}

// Fuses clouds into a new grid with the options' model, voxel size and box (given or fitted to
// all clouds and sensor origins). Each cloud uses its own pose, overridden as options.pose_for says.
// Fused through ScanFusion: precise wherever the grid lies. Throws Error(invalid_argument) for
// bad options, Error(bad_value) if no point is finite or the box or a sensor is out of range.
template <typename PointT>
Grid integrate_clouds(const std::vector<const pcl::PointCloud<PointT>*>& clouds, const ScanOptions& options) {
  options.validate();
  for (const auto* c : clouds)
    if (!c) throw Error(Status::invalid_argument, "null cloud pointer");
  auto pose_of = [&](const pcl::PointCloud<PointT>& c) {
    return options.pose_for(cloud_pose_d(c));
  };
  GridFrame frame;
  if (options.bbox) {
    frame = frame_for_box(*options.bbox, options.voxel_size);
  } else {
    ScanBounds bounds;
    for (const auto* c : clouds) add_cloud_bounds(bounds, *c, pose_of(*c), options.model.max_range);
    frame = bounds.frame(options.voxel_size, options.margin);
  }
  ScanFusion fusion(frame, options.model);
  std::size_t total = 0, before = 0;
  for (const auto* c : clouds) total += c->points.size();
  attach_progress(fusion.fusion(), options, &before, total);
  for (const auto* c : clouds) {
    detail::with_xyz(*c, [&](const float* xyz, std::size_t n, std::size_t stride) {
      fusion.insert(pose_of(*c), xyz, n, stride, options.threads);
    });
    before += c->points.size();
  }
  if (!fusion.fusion().rays()) throw Error(Status::bad_value, "no finite point in the cloud(s)");
  return fusion.grid();
}

// One cloud (see integrate_clouds).
template <typename PointT>
Grid integrate_cloud(const pcl::PointCloud<PointT>& cloud, const ScanOptions& options) {
  return integrate_clouds<PointT>({&cloud}, options);
}

// Shared-pointer clouds, as PCL code usually holds them (see integrate_clouds).
template <typename PointT>
Grid integrate_clouds(const std::vector<std::shared_ptr<pcl::PointCloud<PointT>>>& clouds, const ScanOptions& options) {
  std::vector<const pcl::PointCloud<PointT>*> raw;
  for (const auto& c : clouds) {
    if (!c) throw Error(Status::invalid_argument, "null cloud pointer");
    raw.push_back(c.get());
  }
  return integrate_clouds<PointT>(raw, options);
}

// The voxel centres of the chosen states as a cloud, label = segment id, voxels in index order
// (x fastest). `grid` gives the frame the result was computed on. Throws Error(invalid_argument)
// when grid and result disagree in dims.
pcl::PointCloud<pcl::PointXYZL> labelled_cloud(const Grid& grid, const Result& result, StateSet states = StateSet());

// One cloud per segment, indexed by segment id; segments of unchosen states get an empty cloud.
std::vector<pcl::PointCloud<pcl::PointXYZL>> segment_clouds(const Grid& grid, const Result& result,
                                                            StateSet states = StateSet());

// Instantiated once in liboccseg_pcl for the common point types.
#define OCCSEG_PCL_EXTERN(T)                                                                                   \
  extern template void insert_cloud<T>(OccupancyFusion&, const pcl::PointCloud<T>&, const Eigen::Isometry3f&, \
                                       int);                                                                   \
  extern template void insert_cloud<T>(OccupancyFusion&, const pcl::PointCloud<T>&, int);                     \
  extern template Grid integrate_clouds<T>(const std::vector<const pcl::PointCloud<T>*>&, const ScanOptions&); \
  extern template Grid integrate_cloud<T>(const pcl::PointCloud<T>&, const ScanOptions&);
OCCSEG_PCL_EXTERN(pcl::PointXYZ)
OCCSEG_PCL_EXTERN(pcl::PointXYZI)
OCCSEG_PCL_EXTERN(pcl::PointXYZL)
OCCSEG_PCL_EXTERN(pcl::PointXYZRGB)
OCCSEG_PCL_EXTERN(pcl::PointXYZRGBA)
OCCSEG_PCL_EXTERN(pcl::PointXYZRGBL)
OCCSEG_PCL_EXTERN(pcl::PointNormal)
OCCSEG_PCL_EXTERN(pcl::PointXYZRGBNormal)
OCCSEG_PCL_EXTERN(pcl::PointXYZINormal)
#undef OCCSEG_PCL_EXTERN

}  // namespace occseg
