// PCL .pcd files in and labelled voxel clouds out, behind a PCL-free interface (liboccseg_pcl).
// Code that has PCL types at hand can use occseg/pcl_cloud.hpp instead.
#pragma once
#include <string>

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

// Reads a .pcd file (ascii, binary or binary_compressed; organized or not) with PCL's reader and
// fuses it into a probabilistic grid by ray casting from the sensor: the file's VIEWPOINT unless
// options.sensor_pose overrides it. NaN points (holes of organized clouds) are skipped.
// Throws Error(io) when the file cannot be opened, Error(format) when it is corrupt, truncated
// or has no x/y/z float fields, Error(bad_value) when no point is finite; messages name the file.
Grid read_pcd(const std::string& path, const ScanOptions& options);

// Writes the voxel centres of the chosen states as a binary PointXYZL .pcd (label = segment id),
// atomically (or staged `into` a set of files replaced together). `grid` gives the frame (origin, voxel size) the result was computed on.
// Throws Error(invalid_argument) when grid and result disagree in dims, Error(io) on write failure.
void write_segments_pcd(const std::string& path, const Grid& grid, const Result& result,
                        StateSet states = StateSet(), StagedFiles* into = nullptr);

}  // namespace occseg
