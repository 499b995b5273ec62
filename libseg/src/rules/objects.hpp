// Objects out of segments (docs/algorithm.md, default preset rules 6-8): proximity across ray
// gaps, speckles, pockets; and the scene table's kinds. They run on the labels and the segment
// table after the labelling and before the support planes.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"

namespace occseg {

// Joins segments (labels and table changed in place; ids stay dense, in the order of each
// segment's first voxel):
//  - proximity (params.object_gap > 0): occupied segments joined by a 6-connected path of at most
//    object_gap voxels that are all unknown become one segment (transitively);
// (Minimum sizes as minimum_size() gives them for the map.)
//  - speckles (params.min_object_voxels > 0): an occupied group (after proximity) of fewer voxels
//    joins the group of at least that many voxels nearest to it (squared distance between voxel
//    centres; ties: the group of the smaller id) whose voxel lies within object_gap + 1 voxels on
//    every axis of one of its own; the others stay as they are (clutter, assign_kinds);
//  - pockets (params.min_pocket_voxels > 0): every free segment but the largest with fewer voxels
//    becomes unknown and joins the unknown segments it touches (6-neighbours); an unknown group
//    of fewer voxels that touches occupied voxels then joins the occupied group it shares the
//    most faces with (ties: the smaller id).
// A merged segment's mean occupancy, centroid and box are its members' combined in id order. The
// visit of the unknown segments' and pockets' faces and the final relabelling (one pass over the
// map, or the moved segments' boxes band of planes by band) run on `params.threads` in fixed
// pieces, whose findings are taken in piece order; the groups are a
// closure and do not depend on the order of the joins: the result never depends on the threads.
// `band_voxels` (per segment id, or nullptr): voxels the surface band (rules/surface_band.hpp)
// added, which rule 7 leaves out of a group's size: the band is inferred from the surface beside
// it, so it never makes a fragment of surface an object of its own.
void group_objects(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                   const std::vector<std::uint64_t>* band_voxels = nullptr);

// Each segment's kind from its state: free, unknown, and for occupied segments structure (when
// the support-plane rule marked it so), clutter (fewer than params.min_object_voxels voxels) or
// object.
void assign_kinds(std::vector<Segment>& segments, const Params& params, const Dims& dims);

// A minimum size parameter (min_object_voxels, min_pocket_voxels) on a map of `dims`: the value
// itself, but on a one-layer map (nz = 1) the area of a square whose side is its cube's edge,
// round(v^(2/3)) cells (27 -> 9, 64 -> 16): a 2D map's regions are areas, not volumes. 0: off.
std::uint64_t minimum_size(int voxels, const Dims& dims);

}  // namespace occseg
