// Holes in a plane (docs/algorithm.md, default preset rule 12): free voxels that rays grazing a
// thin surface left inside it. A table top two voxels thick, seen edge-on by a planar scanner, is
// crossed from rim to rim by rays that pass through the part of its rim voxels outside the solid;
// those voxels are free-valued, and thick (free space lies above and below them), so the surface
// band (rule 10) does not take them. Rule 11 has found the top's plane; its free voxels lying in
// the plane's inlier band, between the top's own voxels, are such holes.
#pragma once
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"
#include "rules/structure.hpp"

namespace occseg {

// Only pieces seen edge-on are used: free space on both sides (from the piece's voxels, one to
// three voxels along the normal's axis, the first voxel outside its segment is free on each side
// at least a quarter as often as on the other) and no other piece of its segment parallel to it
// (within 10 degrees) within 2.5 voxel edges with overlapping boxes (a surface seen face-on under
// range noise spreads over parallel layers, each a piece). For each such piece, in order: the
// free voxels within kPlaneInlierDistance of its plane and inside its extent whose run of free
// voxels along one of the two grid axes other than the one nearest its normal, within that
// distance of the plane, has at most params.plane_holes voxels and ends on both sides at a
// non-free voxel within that distance, one of them an occupied voxel thin along the normal as
// rule 11 counts it (at most max(4, object_gap + 2) voxels of its segment, crossing gaps of at
// most object_gap), become occupied and join the piece's segment (the label of its inlier
// `voxel`); a voxel claimed by several pieces goes with the first. Everything is decided on the
// labels as they were (no cascade), then applied; a free segment that would lose all its voxels
// keeps them. Statistics: the grown segments' are combined with the new voxels', the free
// segments' have them taken out (voxels, boxes exactly: a box is recomputed from the segment's
// voxels when a voxel taken lay on its face; the mean occupancy and the centroid as
// voxel-weighted means). One thread: results never depend on params.threads. Nothing is done
// when params.plane_holes is 0.
void fill_plane_holes(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                      const std::vector<PlanePiece>& pieces);

}  // namespace occseg
