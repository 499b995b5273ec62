// Small synthetic maps whose segmentation is known by construction.
#pragma once
#include "occseg/grid.hpp"

namespace occseg::test {

constexpr float kFreeP = 0.12f, kOccP = 0.97f, kHalf = 0.5f;

// Fills [x0,x1) x [y0,y1) x [z0,z1) with value v.
inline void box(Grid& g, int x0, int y0, int z0, int x1, int y1, int z1, float v) {
  for (int z = z0; z < z1; ++z)
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) g.at(x, y, z) = v;
}

}  // namespace occseg::test
