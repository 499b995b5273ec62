// Analytic solids of the simulated scenes, with exact ray intersection. All solids are
// axis-aligned and described by their bounding box: a box is the box itself; a cylinder and a
// cone stand upright (axis along z) on the bottom face of the box, centred in it, with the
// radius half the box's x extent (the box must be square in x and y). The cone's apex is at the
// centre of the top face.
#pragma once
#include <cstdint>

#include "occseg/fusion.hpp"

namespace occseg::sim {

enum class ShapeKind { box, cylinder, cone };
const char* shape_kind_name(ShapeKind k);

struct Shape {
  ShapeKind kind = ShapeKind::box;
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};  // bounding box, world metres
  std::uint16_t object = 1;       // ground-truth object id (>= 1); several shapes may share one

  double radius() const { return 0.5 * (hi[0] - lo[0]); }
  double cx() const { return 0.5 * (lo[0] + hi[0]); }
  double cy() const { return 0.5 * (lo[1] + hi[1]); }
};

// Builders. Throw Error(invalid_argument) for an empty box, a non-positive radius or height,
// or object id 0.
Shape make_box(const Vec3& lo, const Vec3& hi, std::uint16_t object);
Shape make_cylinder(double cx, double cy, double z0, double z1, double radius, std::uint16_t object);
Shape make_cone(double cx, double cy, double z0, double z1, double base_radius, std::uint16_t object);

// True when point p lies in the closed solid.
bool contains(const Shape& s, const Vec3& p);

// The smallest t >= 0 at which the ray o + t d is in the solid: the entry distance (in units of
// |d|), 0 when o is inside, +infinity when the ray misses. d need not be normalised but must not
// be zero.
double intersect(const Shape& s, const Vec3& o, const Vec3& d);

}  // namespace occseg::sim
