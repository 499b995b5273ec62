// `occseg segment` input dispatch: picks the reader by file extension and says which outputs the
// input kind gets. The only place the tool knows about PCL and OctoMap (through their PCL-free
// adapter headers); a build without them reports Error(unsupported) for those extensions.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"
#include "occseg/segment.hpp"

namespace occseg::cli {

struct MapInputOptions {
  std::optional<double> voxel_size;               // .npy: default 1; clouds: default 0.05 m; trees: resolution
  std::optional<std::array<double, 6>> bbox;      // xmin ymin zmin xmax ymax zmax (metres)
  std::optional<std::array<double, 3>> sensor_origin;       // clouds: overrides the stored viewpoint
  std::optional<std::array<double, 4>> sensor_orientation;  // w x y z; with or without an origin
  double max_range = -1;                          // clouds: metres, < 0 unlimited
  std::string coarsen;                            // trees at a coarser voxel size: max or mean; empty: max
  int threads = 0;
  std::function<bool(double fraction)> progress;  // clouds: fusion progress (ScanOptions::progress)
  // Progress of reading the file (.npy, .nrrd, .bt, .ot): fraction 0..1; false cancels.
  std::function<bool(double fraction)> read_progress;
};

enum class InputKind { volume, cloud, tree, map2d };  // map2d: a map_server .yaml map

struct MapInput {
  Grid grid;
  InputKind kind = InputKind::volume;
  std::string format;  // for people: "NumPy .npy, float32, C order", "PCL point cloud (.pcd), 209280 ..."
  // The named space of a .nrrd input (teem's name, e.g. "left-posterior-superior"): the grid is
  // in its coordinates, and labels.nrrd is written in it. Empty for every other input.
  std::string nrrd_space;
  // .pcd inputs (issue 26): the segment id of each input point, in file order (UINT32_MAX: a NaN
  // point, or one outside the grid), and a writer of the input cloud with a `label` field.
  // Empty for every other input. A label image for organized clouds: point_shape is {height,
  // width} then, {count} otherwise.
  std::function<std::vector<std::uint32_t>(const Grid&, const Result&)> point_labels;
  std::vector<std::size_t> point_shape;
  std::function<void(const std::string& path, const std::vector<std::uint32_t>& labels, StagedFiles& into)>
      write_points_pcd;
};

// Reads .npy, .nrrd, .yaml (map_server), .pcd, .graph, .bt or .ot (case-insensitive extension). Throws
// Error(invalid_argument) for an unknown extension or an option the format cannot use,
// Error(unsupported) for a format this build lacks, and the readers' errors otherwise.
MapInput load_map(const std::string& path, const MapInputOptions& options);

// Writes the voxel centres of occupied segments as a PointXYZL .pcd (label = segment id).
// Throws Error(unsupported) in a build without PCL. `into`: as write_file_atomically.
void write_cloud_output(const std::string& path, const Grid& grid, const Result& result, StagedFiles* into = nullptr);
bool have_pcl();

// segments.ot: the occupied segments as an OctoMap ColorOcTree (occseg/octomap_segments.hpp).
// Returns true when the map's origin was off OctoMap's lattice and the tree was moved onto it,
// with the shift (metres) in `shift`. Throws Error(unsupported) in a build without OctoMap.
bool write_octree_output(const std::string& path, const Grid& grid, const Result& result, StagedFiles* into,
                         std::array<double, 3>* shift);
bool have_octomap();
// True for the OctoMap input formats (.bt, .ot, .graph), whose default outputs include segments.ot.
bool is_octomap_input(const std::string& path);

}  // namespace occseg::cli
