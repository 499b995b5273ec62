// Options and helpers shared by the readers that fuse range scans into a grid (PCL clouds,
// OctoMap scan graphs). Free of PCL and OctoMap: only the core and header-only Eigen.
//
// Pose convention (as OctoMap's insertPointCloud(cloud, sensor_origin, frame_origin)): a scan's
// points are given in the sensor frame; the pose maps them into the world frame, and the sensor
// sits at pose.translation(). Points already in world coordinates with the sensor elsewhere go
// straight to OccupancyFusion::insert_scan(sensor, xyz, count, stride).
//
// Precision: poses are doubles, and the readers fuse through ScanFusion, which carries points
// relative to the grid's corner, so a map at UTM-like coordinates (5e6 m, where a float is only
// good to 0.5 m) is fused as precisely as one at the world origin. Boxes and sensors more than
// 2^40 voxels from the world origin are refused as out of range (occseg/geometry.hpp).
#pragma once
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>

#include "occseg/fusion.hpp"

namespace occseg {

// An axis-aligned box in world metres.
struct Box {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
};

struct ScanOptions {
  double voxel_size = 0.05;     // metres per voxel edge
  SensorModel model;            // log-odds model and max range (OctoMap's defaults)
  std::optional<Box> bbox;      // grid box; empty: fitted to the points and the sensor origins
  double margin = 0.0;          // metres added on every side of a fitted box
  // Overrides the pose stored with the data (a cloud's sensor_origin_/sensor_orientation_,
  // a scan graph node's pose); applied to every scan. Double, so that a sensor far from the
  // world origin keeps its position to the millimetre and better (make_pose).
  std::optional<Eigen::Isometry3d> sensor_pose;
  // Override one half of the stored pose each, keeping the other (what --sensor-origin and
  // --sensor-orientation do): the sensor's position, and its rotation as a quaternion (w, x, y, z),
  // normalised as make_pose normalises it. Applied to every scan; ignored when sensor_pose is set.
  std::optional<Vec3> sensor_origin;
  std::optional<std::array<double, 4>> sensor_orientation;
  // The pose a scan stored with pose `stored` is fused from under these options.
  Eigen::Isometry3d pose_for(const Eigen::Isometry3d& stored) const;
  int threads = 0;              // 0: all cores; results never depend on it
  // Called while fusing with the share of all points ray-cast so far, in [0, 1], from the
  // calling thread; returning false cancels: the reader throws Error(cancelled).
  std::function<bool(double fraction)> progress;
  // Throws Error(invalid_argument / bad_value) naming the field when a value is out of range.
  void validate() const;
};

// The grid frame over a given box: origin at box.min, ceil(extent / voxel_size) voxels per
// axis (at least 1). Throws Error(bad_value) for an empty, inverted or non-finite box or one out
// of range (check_geometry) and Error(bad_dims) when it needs too many voxels.
GridFrame frame_for_box(const Box& box, double voxel_size);

// Accumulates the bounding box of sensor origins and scan endpoints (in world coordinates),
// for fitting a grid to the data before fusing it. Non-finite points are ignored; endpoints
// beyond the max range count only up to the max range, since that is all the ray reaches.
class ScanBounds {
 public:
  // Adds a scan of `count` points (x, y, z floats, `stride` floats apart) in the sensor frame,
  // transformed in double.
  void add(const Eigen::Isometry3d& pose, const float* xyz, std::size_t count, std::size_t stride,
           double max_range);
  void add(const Eigen::Isometry3f& pose, const float* xyz, std::size_t count, std::size_t stride,
           double max_range) {
    add(Eigen::Isometry3d(pose.cast<double>()), xyz, count, stride, max_range);
  }
  // Same for points in double (the C ABI's and Python's float64 clouds).
  void add(const Eigen::Isometry3d& pose, const double* xyz, std::size_t count, std::size_t stride,
           double max_range);
  bool empty() const { return !any_; }
  // The smallest voxel-aligned frame holding everything added, padded by `margin` metres
  // (fit_frame of the core). Throws Error(bad_value) if nothing finite was added, and "points or
  // sensor origins at x = ... m: out of range, ..." when they reach beyond 2^40 voxels from the
  // world origin.
  GridFrame frame(double voxel_size, double margin) const;

 private:
  void extend(const Vec3& p);
  template <class T>
  void add_points(const Eigen::Isometry3d& pose, const T* xyz, std::size_t count, std::size_t stride,
                  double max_range);
  bool any_ = false;
  Vec3 lo_{0, 0, 0}, hi_{0, 0, 0};
};

// Inserts one scan given in the sensor frame: transforms the points by `pose` (without a copy
// when the pose is the identity) and ray-casts from pose.translation(). The points become world
// coordinates in float: exact enough near the world origin only; far from it (UTM coordinates)
// use ScanFusion.
void insert_points(OccupancyFusion& fusion, const Eigen::Isometry3f& pose, const float* xyz,
                   std::size_t count, std::size_t stride, int threads = 0);

// Fuses scans into the grid of a world frame wherever it lies. The core's fusion takes float
// endpoints, and a float of a world coordinate far from the origin is coarse (0.5 m at 5e6 m);
// so the fusion here works in coordinates relative to the frame's corner, computed in double
// from the sensor-frame points and the pose before they become floats. The grid comes back in
// world coordinates. What the readers (read_pcd, integrate_clouds, read_scan_graph) use.
class ScanFusion {
 public:
  ScanFusion(const GridFrame& frame, const SensorModel& model);
  // One scan of `count` points (x, y, z floats, `stride` floats apart) in the sensor frame, seen
  // from `pose`. Throws Error(bad_value) "sensor origin at x = ... m: out of range, ..." for a
  // sensor more than 2^40 voxels from the world origin, Error(cancelled) from the progress
  // callback.
  void insert(const Eigen::Isometry3d& pose, const float* xyz, std::size_t count, std::size_t stride,
              int threads = 0);
  // Same for points in double: transformed in double and rounded to float once, so points that
  // are floats widened to double give exactly the grid of the float call.
  void insert(const Eigen::Isometry3d& pose, const double* xyz, std::size_t count, std::size_t stride,
              int threads = 0);
  // The fusion itself (for progress and counts); its frame has the origin (0, 0, 0).
  OccupancyFusion& fusion() { return fusion_; }
  const OccupancyFusion& fusion() const { return fusion_; }
  const GridFrame& frame() const { return frame_; }  // in world coordinates
  // The probabilities, with the world frame's origin.
  Grid grid() const;

 private:
  GridFrame frame_;
  OccupancyFusion fusion_;
};

// The label of a point no voxel holds (non-finite, or outside the grid): UINT32_MAX, as
// OCCSEG_NO_LABEL of the C ABI.
constexpr std::uint32_t kNoPointLabel = 0xffffffffu;

// For each of `count` points of a scan (x, y, z of type T, `stride` elements apart, in the sensor
// frame, seen from `pose`): out[i] = label(voxel index) of the voxel of `frame` (world
// coordinates) the point lies in, computed exactly as ScanFusion::insert and the ray walk compute
// the voxel of its return (endpoint_voxel), or kNoPointLabel when the point is not finite or lies
// outside the grid. T is float or double. Error(bad_value) for a sensor out of range.
template <class T>
void scan_point_voxels(const GridFrame& frame, const Eigen::Isometry3d& pose, const T* xyz, std::size_t count,
                       std::size_t stride, std::uint32_t* out, const std::function<std::uint32_t(std::uint64_t)>& label,
                       int threads = 0);

// Feeds options.progress (if set) from the fusion: the fraction is (before + rays of the current
// scan) / total, where `*before` counts the points of the scans already inserted (the caller
// advances it) and `total` those of all scans.
void attach_progress(OccupancyFusion& fusion, const ScanOptions& options, const std::size_t* before,
                     std::size_t total);

// True when the pose is exactly the identity (no transform needed).
bool is_identity(const Eigen::Isometry3f& pose);
bool is_identity(const Eigen::Isometry3d& pose);

// A pose from a translation and a quaternion (w, x, y, z), normalised (scaled by a power of two
// first, so that no square overflows or underflows: (1e200, 1e200, 0, 0) is a turn of 90 degrees
// about x, not the identity). Throws Error(bad_value) for a non-finite value or a zero quaternion.
Eigen::Isometry3d make_pose(const Vec3& origin, const std::array<double, 4>& wxyz = {1, 0, 0, 0});

}  // namespace occseg
