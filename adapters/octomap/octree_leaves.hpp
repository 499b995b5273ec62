// The leaves of an OctoMap tree as the dense grid is painted from them (internal to
// liboccseg_octomap): from an OctoMap tree object (octree_grid.cpp) or straight from the checked
// bytes of a .bt file (octree_file.cpp), which then never builds the tree at all.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/octomap_file.hpp"

namespace occseg::octree_detail {

// A leaf: the lower corner key, its side in tree voxels (1 << level, level = 16 - depth) and its
// log-odds.
struct Leaf {
  std::uint16_t key[3];
  std::uint8_t level;
  float log_odds;
};

// The dense grid of OctreeOptions from a tree's leaves in OctoMap's leaf-iterator order (depth
// first, children 0..7); `res` the tree's resolution, `depth` its depth (16). May reorder or
// clear `leaves`. The errors of grid_from_octree.
Grid grid_from_leaves(std::vector<Leaf>& leaves, double res, int depth, const OctreeOptions& options);

}  // namespace occseg::octree_detail
