// Small hand-made scenes for the simulator tests.
#pragma once
#include "occseg/sim/scene.hpp"

namespace occseg::sim::test {

// A 20 x 10 x 1 map of 10 cm voxels with a wall across it whose face is at x = 1.23 m (inside
// voxel 12), and one planar scanner at (0.05, 0.5) looking along +x with a 180 degree fan.
inline Scene wall_scene(double heading_deg = 0) {
  Scene s;
  s.name = "wall";
  s.frame.dims = Dims{20, 10, 1};
  s.frame.voxel_size = 0.1;
  s.objects = {"wall"};
  s.shapes = {make_box({1.23, -1, -1}, {1.57, 2, 2}, 1)};
  Viewpoint v;
  v.position = {0.05, 0.5, 0.05};
  v.heading_deg = heading_deg;
  s.viewpoints = {v};
  return s;
}

}  // namespace occseg::sim::test
