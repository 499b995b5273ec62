// segments.ot: the occupied voxels of a segmentation as an OctoMap ColorOcTree, coloured by
// segment (liboccseg_octomap), for octovis and RViz's OctoMap display. OctoMap-free interface;
// occseg/octomap_tree.hpp has the version that returns the tree itself.
#pragma once
#include <array>
#include <string>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"
#include "occseg/result.hpp"

namespace occseg {

// How the map's voxels were placed on OctoMap's lattice. An OctoMap tree has no origin: its
// voxels of resolution r have their corners at whole multiples of r from the world origin (a
// point c has key floor(c / r) + 32768 on each axis, and key k the centre (k - 32768 + 0.5) r).
// The map's voxels land exactly on the tree's leaves when its origin is a whole number of voxels
// (within 1e-6 of a voxel); otherwise the whole map is moved by `shift` (metres, each component
// at most half a voxel) to the nearest lattice position, and `snapped` is true.
struct OctreePlacement {
  std::array<double, 3> shift{0, 0, 0};
  bool snapped = false;
};

// Writes every voxel of every occupied segment as one leaf at the tree's full depth (16, voxel
// size = the tree's resolution), with the colour of its segment (occseg/segment_colour.hpp) and
// the voxel's occupancy probability, raised to at least 0.7 (OctoMap's probability of one hit)
// so that octovis and RViz count it occupied. Free and unknown space are not stored (unknown in
// the tree). Leaves are never pruned: eight neighbours of different segments keep their own
// colours (OctoMap's ColorOcTree would merge equal occupancies regardless of colour). Inner nodes
// hold the maximum occupancy and the average colour of their children, as OctoMap's
// updateInnerOccupancy makes them.
// Throws Error(bad_value) when the map does not fit OctoMap's key range (2^16 voxels per axis
// around the world origin), Error(io) from writing; `into`: as write_file_atomically.
OctreePlacement write_segments_octree(const std::string& path, const Grid& grid, const Result& result,
                                      StagedFiles* into = nullptr);

}  // namespace occseg
