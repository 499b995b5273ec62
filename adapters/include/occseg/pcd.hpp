// PCL .pcd files in and labelled voxel clouds out, behind a PCL-free interface (liboccseg_pcl).
// Code that has PCL types at hand can use occseg/pcl_cloud.hpp instead.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/scan_options.hpp"
#include "occseg/segment.hpp"

namespace occseg {

class StagedFiles;  // occseg/file_write.hpp

// Which voxel states go into an output cloud.
struct StateSet {
  bool free = false, unknown = false, occupied = true;
  bool has(State s) const {
    return s == State::free ? free : (s == State::unknown ? unknown : occupied);
  }
  static StateSet all() { return {true, true, true}; }
};

// The points of a .pcd file as read_pcd fused them, kept for putting the segmentation back on
// them (read_pcd's `cloud` argument): the points in the file's own (sensor) frame, the pose they
// were fused with, and every field of the file, for writing the cloud again with a label field.
struct PcdCloud {
  struct Field {
    std::string name;
    char type = 'F';                  // I, U or F
    unsigned size = 4, count = 1;     // bytes per element, elements
    std::size_t offset = 0;           // in a point of `data`
  };
  std::size_t width = 0, height = 0;  // height > 1: an organized cloud, width points a row
  std::vector<float> xyz;             // width * height points, x, y, z, in file order (NaN kept)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // the fusion's: VIEWPOINT or override
  std::array<double, 7> viewpoint{0, 0, 0, 1, 0, 0, 0};     // the file's VIEWPOINT, as PCL read it
  std::vector<Field> fields;          // the file's fields, padding ("_") included
  std::size_t point_step = 0;         // bytes per point in `data`
  std::vector<std::uint8_t> data;     // width * height points of point_step bytes
};

// Reads a .pcd file (ascii, binary or binary_compressed; organized or not) with PCL's reader and
// fuses it into a probabilistic grid by ray casting from the sensor: the file's VIEWPOINT unless
// options.sensor_pose overrides it. NaN points (holes of organized clouds) are skipped.
// Throws Error(io) when the file cannot be opened, Error(format) when it is corrupt, truncated
// or has no x/y/z float fields, Error(bad_value) when no point is finite; messages name the file.
Grid read_pcd(const std::string& path, const ScanOptions& options);
// Same, and fills `*cloud` with the file's points (for pcd_point_labels and write_points_pcd).
Grid read_pcd(const std::string& path, const ScanOptions& options, PcdCloud* cloud);

// The segment id of each point of `cloud` (file order), computed as the fusion computed the voxel
// of its return (scan_point_voxels); kNoPointLabel (UINT32_MAX) for NaN points and points outside
// the grid. `grid` gives the frame the result was computed on.
std::vector<std::uint32_t> pcd_point_labels(const PcdCloud& cloud, const Grid& grid, const Result& result,
                                            int threads = 0);

// Writes the cloud as read, in its own frame (same VIEWPOINT, WIDTH and HEIGHT, every field), with
// a uint32 field `label` appended (an existing field of that name is replaced), as DATA binary;
// atomically or staged `into` a set of files. Error(invalid_argument) if labels do not match.
void write_points_pcd(const std::string& path, const PcdCloud& cloud, const std::vector<std::uint32_t>& labels,
                      StagedFiles* into = nullptr);

// Writes the voxel centres of the chosen states as a binary PointXYZL .pcd (label = segment id),
// atomically (or staged `into` a set of files replaced together). `grid` gives the frame (origin, voxel size) the result was computed on.
// Throws Error(invalid_argument) when grid and result disagree in dims, Error(io) on write failure.
void write_segments_pcd(const std::string& path, const Grid& grid, const Result& result,
                        StateSet states = StateSet(), StagedFiles* into = nullptr);

}  // namespace occseg
