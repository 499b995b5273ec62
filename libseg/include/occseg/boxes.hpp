// Oriented bounding boxes of segments, in metres: boxes to plan with (a MoveIt collision object
// per occupied segment). Computed from a Result's labels on request, never by segment() itself.
#pragma once
#include <array>
#include <vector>

#include "occseg/result.hpp"

namespace occseg {

// A box in the map's world frame: `center` (metres), full edge lengths `extents` (metres) along
// the box's own axes, and the rotation from the map's axes to the box's axes as a unit
// quaternion (w, x, y, z), w >= 0: a point at local coordinates q lies at center + R(q) q.
struct OrientedBox {
  std::array<double, 3> center{0, 0, 0};
  std::array<double, 3> extents{0, 0, 0};
  std::array<double, 4> quaternion{1, 0, 0, 0};
};

// One box per segment (index = id), for a map of `voxel_size` metres whose voxel (0, 0, 0) has
// its outer corner at `origin`.
//
// Occupied segments: the smallest box, by volume, among three candidate orientations that holds
// every voxel of the segment whole (each voxel a cube, not a point): the map's axes; the
// principal axes of the voxel centres (PCA: eigenvectors of their covariance, largest variance
// first); and a turn about z alone, the minimum-area rectangle of the voxels seen from above
// (tried along every edge of the convex hull of the voxel centres' (x, y)), for objects standing
// on a floor. Ties keep the earlier candidate, so an axis-aligned object gets the identity
// rotation and exactly its voxel box. Free and unknown segments get their axis-aligned voxel box
// (identity rotation): they are space, not objects to plan around.
//
// Deterministic: one thread, integer moments, a fixed order; the boxes depend only on the labels
// and the segment table, never on the thread count the labels were made with.
// Throws std::bad_alloc when the voxel lists of the occupied segments do not fit in memory.
std::vector<OrientedBox> oriented_boxes(const Result& result, double voxel_size, const std::array<double, 3>& origin);

}  // namespace occseg
