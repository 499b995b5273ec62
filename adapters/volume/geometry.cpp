#include "occseg/geometry.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "occseg/error.hpp"

namespace occseg {

namespace {

std::string g(double v) {
  char t[64];
  std::snprintf(t, sizeof t, "%g", v);
  return t;
}

std::string range_text(double voxel_size) {
  return "more than 2^40 voxels of " + g(voxel_size) + " m (" + g(kMaxCoordinateVoxels * voxel_size) +
         " m) from the world origin";
}

}  // namespace

void check_coordinate(double c, int axis, double voxel_size, const char* what) {
  // Divided, not multiplied: kMaxCoordinateVoxels * voxel_size may overflow.
  if (!std::isfinite(c) || !(std::fabs(c) / voxel_size <= kMaxCoordinateVoxels))
    throw Error(Status::bad_value, std::string(what) + " at " + "xyz"[axis] + " = " + g(c) + " m: out of range, " +
                                       range_text(voxel_size));
}

void check_geometry(const Dims& d, double voxel_size, const std::array<double, 3>& origin) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw Error(Status::bad_value, "voxel size " + g(voxel_size) + " is not a positive finite number");
  const std::size_t n[3] = {d.nx, d.ny, d.nz};
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(origin[k]))
      throw Error(Status::bad_value, "origin " + std::string(1, "xyz"[k]) + " = " + g(origin[k]) + " is not finite");
    const double far = origin[k] + static_cast<double>(n[k]) * voxel_size;  // may be inf
    if (!(std::fabs(origin[k]) / voxel_size <= kMaxCoordinateVoxels) ||
        !(std::fabs(far) / voxel_size <= kMaxCoordinateVoxels))
      throw Error(Status::bad_value, "map extent in " + std::string(1, "xyz"[k]) + " from " + g(origin[k]) + " to " +
                                         g(far) + " m: out of range, " + range_text(voxel_size));
  }
}

}  // namespace occseg
