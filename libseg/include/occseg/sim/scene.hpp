// A simulated environment: a box of voxels, analytic solids in it, and the range sensor's points
// of view. The catalogue reproduces the paper's three scenes (section 4: a cone, a cube and a
// cylinder in a 320 x 320 x 128 map) and adds scenes that stress its claims (docs/experiments.md).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/fusion.hpp"
#include "occseg/sim/shapes.hpp"

namespace occseg::sim {

// A point of view. In the planar construction only x and y are used: the scanner sits at the
// height of each layer in turn. Angles in degrees; heading 0 looks along +x, 90 along +y.
struct Viewpoint {
  Vec3 position{0, 0, 0};
  double heading_deg = 0;
  double fov_deg = 180;        // horizontal field of view, centred on the heading (<= 360)
  double pitch_min_deg = -45;  // full 3D scans only: vertical field of view
  double pitch_max_deg = 45;
};

// A slice worth looking at in a figure: axis 0/1/2 (x/y/z) and the voxel index along it.
struct SliceHint {
  int axis = 2;
  std::size_t index = 0;
};

struct Scene {
  std::string name;
  GridFrame frame;                   // dims, voxel size, origin (0, 0, 0)
  std::vector<Shape> shapes;
  std::vector<std::string> objects;  // objects[i] is the name of object id i + 1
  std::vector<Viewpoint> viewpoints;
  std::vector<SliceHint> slices;     // for figures
};

// Names accepted by make_scene, in catalogue order.
const std::vector<std::string>& scene_names();

// Builds a catalogue scene for a map of `dims` voxels of `voxel_size` metres. Sizes and positions
// are defined for a 6.4 x 6.4 x 2.56 m room and scale with the map's extent (the default, the
// paper's 320 x 320 x 128 voxels of 4 cm, is a 12.8 x 12.8 x 5.12 m hall: docs/experiments.md
// explains the choice), so every map shows the same picture and small maps make fast tests. Throws Error(invalid_argument) naming the
// scene for an unknown name, and Error(bad_dims) for dims below 16 x 16 x 8.
Scene make_scene(const std::string& name, const Dims& dims = Dims{320, 320, 128}, double voxel_size = 0.04);

// The first solid met by the ray o + t d, d a unit vector: returns t (metres), +infinity when
// nothing is hit, and the solid's object id in *object (0 when nothing is hit).
double first_hit(const Scene& scene, const Vec3& o, const Vec3& d, std::uint16_t* object = nullptr);

// Throws Error(invalid_argument) naming the problem for a scene with no viewpoint, an object id
// without a name, or a viewpoint with a bad field of view.
void validate_scene(const Scene& scene);

}  // namespace occseg::sim
