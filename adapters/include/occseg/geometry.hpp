// The geometry (voxel size, origin, extent) a map must have to be placed in the world, written
// and read back: one rule for every reader, writer and map the C ABI builds, so that no file is
// written that occseg's own readers refuse.
#pragma once
#include <array>
#include <cstddef>

#include "occseg/grid.hpp"

namespace occseg {

// How far from the world origin a map's box may reach, in voxels (2^40, as kMaxVoxels). Within
// it a world coordinate in double is exact to 2^-12 of a voxel, so voxel corners stay distinct
// and points fall into the right voxel; beyond it (or where the extent overflows to infinity)
// a map is refused rather than silently collapsed.
constexpr double kMaxCoordinateVoxels = static_cast<double>(std::size_t(1) << 40);

// Throws Error(bad_value) naming the problem unless the voxel size is positive and finite, the
// origin is finite, and both corners of the box, origin and origin + dims * voxel_size, lie
// within kMaxCoordinateVoxels voxels of the world origin.
void check_geometry(const Dims& dims, double voxel_size, const std::array<double, 3>& origin);
inline void check_geometry(const Grid& g) { check_geometry(g.dims, g.voxel_size, g.origin); }

// Throws Error(bad_value) "<what> at x = 1e+30 m: out of range, ..." when |coordinate| exceeds
// kMaxCoordinateVoxels voxels of `voxel_size` (or is not finite). For data and sensors.
void check_coordinate(double coordinate, int axis, double voxel_size, const char* what);

}  // namespace occseg
