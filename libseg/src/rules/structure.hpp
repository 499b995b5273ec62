// Structure and objects (docs/algorithm.md, default preset rule 11): several planes per occupied
// segment. The support-plane rule (rules/planes.hpp) splits a segment that one plane holds half of;
// a building's floor, walls and ceiling are one connected segment that no single plane holds half
// of, with the furniture standing on and against them. This rule finds those planes, keeps them
// (and what lies flat on them) as one `structure` segment and splits off what stands on or
// against them as objects. It runs before the support planes (which skip the segments it made
// structure) and the kinds.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"

namespace occseg {

// A piece of a plane that rule 11 keeps for coplanar fragments (a structural piece, or a piece of
// at least support_plane voxels of a segment left whole), for rule 12 (rules/plane_holes.hpp):
// the plane n . x = d (x in voxel indices), its principal axes u, v in the plane with the
// inliers' extent along them [u0, u1] x [v0, v1], the box of its inliers, and one inlier (a voxel
// index): its label after split_structure is the piece's segment.
struct PlanePiece {
  std::array<double, 3> n{0, 0, 1};
  double d = 0;
  std::array<double, 3> u{}, v{};
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
  std::array<std::uint32_t, 3> lo{}, hi{};
  std::uint64_t voxel = 0;
};

// For every occupied segment with at least 2 x support_plane voxels, at least half of a 4096-voxel
// sample of which is thin along some axis (at most max(4, object_gap + 2) voxels through it,
// crossing gaps of at most object_gap): for z, then y, then x, planes with normals within 45
// degrees of the axis are searched among the voxels thin along it that no earlier plane holds
// (fit_dominant_plane(..., axis); at most params.structure_planes searches per axis, stopping at
// the first plane of fewer than support_plane voxels). A plane's inliers fall into pieces: cells
// of max(2, object_gap) voxels in the plane's coordinates, 8-adjacent cells joined (a surface with
// ray gaps is one piece). A piece is structural when it has at least support_plane voxels, spans
// params.structure_extent metres along both of its principal axes, is an area (a quarter of its
// cells have all four in-plane neighbours) and is flat (a quadratic fit of its distances sags by
// under half a voxel edge). Unclaimed voxels on a structural piece's plane over its extent
// (widened by a cell) join it. sigma is a structural piece's noise: the robust spread of the
// voxels near its plane that are thin along its axis and of no other structural piece; the
// voxels of no piece within max(3, 5 sigma) / 2 of it whose run along its axis fits in that band
// are that noise and join it too. A segment with a structural piece becomes `structure`: the
// connected components (occupied_connectivity) of its other voxels become objects (new segments,
// numbered after all others in the order of their first voxel) when they have at least
// max(27, min_object_voxels) voxels, touch a structural piece, lie flat on none (within
// max(3, 5 sigma) of its plane, touching it or over its extent) and lie, for every structural
// piece they touch, on a side of it that sees free space and rise max(3, 5 sigma) above it;
// everything else stays in the structure segment.
//
// Then occupied segments of fewer than max(27, min_object_voxels) (and 2 x support_plane) voxels
// whose every voxel lies within one voxel edge of a piece of at least support_plane voxels found
// above (structural, or of a segment left whole), inside its extent widened by object_gap + 1,
// join that piece's segment (the first such piece in segment and search order): a table top seen
// edge-on by a planar scanner is one surface in many pieces. Ids stay dense (the joined ones
// removed, the order of the others kept).
//
// Nothing is done on a one-layer map (nz = 1). Statistics of changed segments are recomputed (in
// scan order, or combined for joins as in rules/objects.hpp). The plane searches of consecutive
// candidates run side by side on params.threads (then split one after the other, in order), and
// the final relabelling pass too: results never depend on params.threads or the kernels `k`.
// `pieces`, when given, receives the pieces that gathered fragments (in search order).
void split_structure(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                     const kernels::Table& k = kernels::active(), std::vector<PlanePiece>* pieces = nullptr);

}  // namespace occseg
