// The 6 (faces) or 26 (faces, edges, corners) neighbours of a voxel inside a map, for the floods
// of the support-plane split (rule 5) and the structure rule (rule 11).
#pragma once
#include <cstddef>
#include <cstdlib>

#include "occseg/grid.hpp"

namespace occseg {

class VoxelNeighbours {
 public:
  VoxelNeighbours(const Dims& d, bool conn26) : d_(d), conn26_(conn26) {
    const auto sy = static_cast<std::ptrdiff_t>(d.nx), sz = static_cast<std::ptrdiff_t>(d.nx * d.ny);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (wanted(dx, dy, dz)) offsets_[count_++] = dx + dy * sy + dz * sz;
  }

  // Calls f(neighbour index) for the neighbours of voxel i inside the map, z, then y, then x,
  // each from -1 to +1. A voxel off the map's faces takes the precomputed offsets without a test
  // per neighbour (those tests and the coordinates would be most of a flood's work).
  template <class F>
  void for_each(std::size_t i, F&& f) const {
    const std::size_t x = i % d_.nx, y = (i / d_.nx) % d_.ny, z = i / (d_.nx * d_.ny);
    if (x > 0 && y > 0 && z > 0 && x + 1 < d_.nx && y + 1 < d_.ny && z + 1 < d_.nz) {
      for (std::size_t k = 0; k < count_; ++k) f(i + static_cast<std::size_t>(offsets_[k]));
      return;
    }
    for (int dz = -1, k = 0; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!wanted(dx, dy, dz)) continue;
          const std::ptrdiff_t offset = offsets_[k++];
          if ((dx < 0 && x == 0) || (dx > 0 && x + 1 == d_.nx) || (dy < 0 && y == 0) || (dy > 0 && y + 1 == d_.ny) ||
              (dz < 0 && z == 0) || (dz > 0 && z + 1 == d_.nz))
            continue;
          f(i + static_cast<std::size_t>(offset));
        }
  }

 private:
  bool wanted(int dx, int dy, int dz) const {
    const int off = std::abs(dx) + std::abs(dy) + std::abs(dz);
    return off != 0 && (conn26_ || off == 1);
  }

  Dims d_;
  bool conn26_;
  std::ptrdiff_t offsets_[26] = {};
  std::size_t count_ = 0;  // 6 or 26
};

}  // namespace occseg
