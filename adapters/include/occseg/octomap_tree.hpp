// In-memory OctoMap objects to dense grids (liboccseg_octomap). Includes OctoMap headers.
#pragma once
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>
#include <octomap/ScanGraph.h>

#include "occseg/grid.hpp"
#include <memory>

#include "occseg/octomap_file.hpp"
#include "occseg/octomap_segments.hpp"
#include "occseg/result.hpp"
#include "occseg/scan_options.hpp"

namespace occseg {

// A dense grid over options.bbox (or the tree's metric bounding box) at the tree's resolution
// or a whole multiple of it; unknown space is 0.5, known voxels keep the tree's probability
// (coarser voxels: options.coarsen). The grid's origin lies on the tree's voxel grid.
// Throws Error(invalid_argument) for bad options, Error(bad_value) for an empty tree without a
// box, Error(bad_dims) when the box needs too many voxels.
Grid grid_from_octree(const octomap::OcTree& tree, const OctreeOptions& options = OctreeOptions());
Grid grid_from_octree(const octomap::ColorOcTree& tree, const OctreeOptions& options = OctreeOptions());
Grid grid_from_octree(const octomap::OcTreeStamped& tree, const OctreeOptions& options = OctreeOptions());

// Fuses every scan of a graph into one grid: a node's points are in its sensor frame, its pose
// maps them to the world (octomap's insertPointCloud(ScanNode) convention).
Grid integrate_scan_graph(const octomap::ScanGraph& graph, const ScanOptions& options);

// The tree write_segments_octree writes (see occseg/octomap_segments.hpp), and where it put the
// map (`placement`, may be null).
std::unique_ptr<octomap::ColorOcTree> segments_octree(const Grid& grid, const Result& result,
                                                      OctreePlacement* placement = nullptr);

}  // namespace occseg
