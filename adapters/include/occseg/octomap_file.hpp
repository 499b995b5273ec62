// OctoMap files in (liboccseg_octomap), behind an OctoMap-free interface: .bt and .ot trees to a
// dense grid, .graph scan graphs fused into one. Code holding octomap::OcTree objects can use
// occseg/octomap_tree.hpp instead.
#pragma once
#include <functional>
#include <optional>
#include <string>

#include "occseg/grid.hpp"
#include "occseg/scan_options.hpp"

namespace occseg {

// How a coarser voxel combines the tree voxels inside it (unknown ones are ignored; a coarse
// voxel with no known tree voxel is unknown, 0.5).
enum class Coarsen {
  max,   // the largest log-odds: OctoMap's own rule for inner nodes; keeps thin obstacles
  mean,  // the mean probability of the known tree voxels; keeps the grading of .ot maps
};

struct OctreeOptions {
  // Edge of the dense voxels in metres: 0 means the tree's resolution; otherwise a whole
  // multiple of it (within 1e-6), so each dense voxel is a block of tree voxels.
  double voxel_size = 0;
  // The box to convert, in metres, widened to whole dense voxels aligned with the tree's voxel
  // grid. Empty: the tree's metric bounding box (all known leaves, free and occupied).
  std::optional<Box> bbox;
  Coarsen coarsen = Coarsen::max;
  // Progress of read_octree_file and grid_from_octree (fraction 0..1; false cancels).
  std::function<bool(double fraction)> progress;
  // Throws Error(invalid_argument) naming a field that is out of range.
  void validate() const;
};

// Reads a .bt (maximum-likelihood) or .ot (full log-odds) file, chosen by its first line, into
// a dense grid: known voxels get the tree's probability, unknown space 0.5. The structure of the
// file is checked before OctoMap parses it. Throws Error(io) when it cannot be read,
// Error(format) when it is truncated or corrupt, Error(unsupported) for a tree type other than
// OcTree, ColorOcTree and OcTreeStamped, Error(invalid_argument) for a voxel size that is not a
// multiple of the tree's resolution; messages name the file.
Grid read_octree_file(const std::string& path, const OctreeOptions& options = OctreeOptions());

// Reads an OctoMap binary scan graph (.graph: scans with their 6D sensor poses, as written by
// octomap::ScanGraph::writeBinary) and fuses every scan into one grid (see ScanOptions; the node
// poses are used unless options.sensor_pose is set). Same errors as read_octree_file.
Grid read_scan_graph(const std::string& path, const ScanOptions& options);

}  // namespace occseg
