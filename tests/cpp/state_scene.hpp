// A hand-built map of three states (0 free, 1 unknown, 2 occupied) given by a function of the
// voxel, with probabilities to match (0.1, 0.5, 0.9), and the labels the tests' rules leave in it:
// the shared fixture of the rule tests (planes, objects, structure).
#pragma once
#include <cstdint>
#include <functional>
#include <set>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/segment.hpp"

namespace occseg::testing_scene {

struct StateScene {
  Grid grid;
  std::vector<std::uint8_t> states;
  LabelArray labels;
  std::vector<Segment> segments;
  StateScene(Dims d, double voxel_size, const std::function<int(int, int, int)>& state) : grid(d, 0.5f, voxel_size) {
    states.resize(d.count());
    for (std::size_t z = 0; z < d.nz; ++z)
      for (std::size_t y = 0; y < d.ny; ++y)
        for (std::size_t x = 0; x < d.nx; ++x) {
          const std::size_t i = grid.index(x, y, z);
          states[i] = static_cast<std::uint8_t>(state(int(x), int(y), int(z)));
          grid.p[i] = states[i] == 2 ? 0.9f : (states[i] == 1 ? 0.5f : 0.1f);
        }
  }
  std::uint32_t at(int x, int y, int z) const { return labels[grid.index(x, y, z)]; }
  // Ids of the voxels for which `pick` is true.
  std::set<std::uint32_t> ids(const std::function<bool(int, int, int)>& pick) const {
    std::set<std::uint32_t> s;
    for (std::size_t z = 0; z < grid.dims.nz; ++z)
      for (std::size_t y = 0; y < grid.dims.ny; ++y)
        for (std::size_t x = 0; x < grid.dims.nx; ++x)
          if (pick(int(x), int(y), int(z))) s.insert(labels[grid.index(x, y, z)]);
    return s;
  }
};

}  // namespace occseg::testing_scene
