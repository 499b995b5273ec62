// The shapes of the simulated objects (shapes.hpp).
#include "occseg/sim/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "occseg/error.hpp"

namespace occseg::sim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A parameter interval [a, b] on the ray; empty when a > b.
struct Interval {
  double a = -kInf, b = kInf;
  bool empty() const { return a > b; }
  void clip(double lo, double hi) {
    a = std::max(a, lo);
    b = std::min(b, hi);
  }
};

// Parameters where lo <= o + t d <= hi on one axis.
Interval slab(double o, double d, double lo, double hi) {
  if (d == 0) return (o >= lo && o <= hi) ? Interval{} : Interval{1, 0};
  double ta = (lo - o) / d, tb = (hi - o) / d;
  if (ta > tb) std::swap(ta, tb);
  return {ta, tb};
}

// The entry parameter of a convex solid whose intersection with the ray is `iv`.
double entry(const Interval& iv) {
  if (iv.empty() || iv.b < 0) return kInf;
  return std::max(iv.a, 0.0);
}

// Roots of A t^2 + B t + C = 0 where the quadratic is <= 0, intersected with `iv`. The solids are
// convex, so whatever part of {q <= 0} lies inside the z slab is a single interval; for A < 0
// (two pieces) we keep the piece that overlaps `iv`, which is the one in the lower nappe.
Interval quadratic_below_zero(double A, double B, double C, Interval iv) {
  if (A == 0) {
    if (B == 0) return C <= 0 ? iv : Interval{1, 0};
    const double r = -C / B;
    if (B > 0) iv.clip(-kInf, r);
    else iv.clip(r, kInf);
    return iv;
  }
  const double disc = B * B - 4 * A * C;
  if (disc < 0) return A > 0 ? Interval{1, 0} : iv;
  const double s = std::sqrt(disc);
  // Numerically stable roots.
  const double q = -0.5 * (B + (B >= 0 ? s : -s));
  double r1 = q / A, r2 = q != 0 ? C / q : r1;
  if (r1 > r2) std::swap(r1, r2);
  if (A > 0) {
    iv.clip(r1, r2);
    return iv;
  }
  Interval lo = iv, hi = iv;
  lo.clip(-kInf, r1);
  hi.clip(r2, kInf);
  if (lo.empty()) return hi;
  if (hi.empty()) return lo;
  return {std::min(lo.a, hi.a), std::max(lo.b, hi.b)};  // touching at the apex only
}

}  // namespace

const char* shape_kind_name(ShapeKind k) {
  switch (k) {
    case ShapeKind::box: return "box";
    case ShapeKind::cylinder: return "cylinder";
    case ShapeKind::cone: return "cone";
  }
  return "?";
}

Shape make_box(const Vec3& lo, const Vec3& hi, std::uint16_t object) {
  for (int k = 0; k < 3; ++k)
    if (!(hi[k] > lo[k]))
      throw Error(Status::invalid_argument, "box is empty along axis " + std::to_string(k));
  if (object == 0) throw Error(Status::invalid_argument, "object id 0 is reserved for empty space");
  return Shape{ShapeKind::box, lo, hi, object};
}

namespace {
Shape upright(ShapeKind kind, double cx, double cy, double z0, double z1, double r, std::uint16_t object) {
  if (!(r > 0)) throw Error(Status::invalid_argument, std::string(shape_kind_name(kind)) + " radius must be positive");
  if (!(z1 > z0)) throw Error(Status::invalid_argument, std::string(shape_kind_name(kind)) + " height must be positive");
  if (object == 0) throw Error(Status::invalid_argument, "object id 0 is reserved for empty space");
  return Shape{kind, {cx - r, cy - r, z0}, {cx + r, cy + r, z1}, object};
}
}  // namespace

Shape make_cylinder(double cx, double cy, double z0, double z1, double radius, std::uint16_t object) {
  return upright(ShapeKind::cylinder, cx, cy, z0, z1, radius, object);
}

Shape make_cone(double cx, double cy, double z0, double z1, double base_radius, std::uint16_t object) {
  return upright(ShapeKind::cone, cx, cy, z0, z1, base_radius, object);
}

bool contains(const Shape& s, const Vec3& p) {
  for (int k = 0; k < 3; ++k)
    if (p[k] < s.lo[k] || p[k] > s.hi[k]) return false;
  if (s.kind == ShapeKind::box) return true;
  const double dx = p[0] - s.cx(), dy = p[1] - s.cy(), r = s.radius();
  const double allowed = s.kind == ShapeKind::cylinder ? r : r * (s.hi[2] - p[2]) / (s.hi[2] - s.lo[2]);
  return dx * dx + dy * dy <= allowed * allowed;
}

double intersect(const Shape& s, const Vec3& o, const Vec3& d) {
  Interval iv = slab(o[2], d[2], s.lo[2], s.hi[2]);
  if (s.kind == ShapeKind::box) {
    for (int k = 0; k < 2; ++k) {
      const Interval a = slab(o[k], d[k], s.lo[k], s.hi[k]);
      iv.clip(a.a, a.b);
    }
    return entry(iv);
  }
  if (iv.empty()) return kInf;
  const double ox = o[0] - s.cx(), oy = o[1] - s.cy(), r = s.radius();
  double A = d[0] * d[0] + d[1] * d[1];
  double B = 2 * (ox * d[0] + oy * d[1]);
  double C = ox * ox + oy * oy;
  if (s.kind == ShapeKind::cylinder) {
    C -= r * r;
  } else {
    // x^2 + y^2 <= (k (z1 - z))^2 with k = r / height; h(t) = z1 - oz - t dz.
    const double k = r / (s.hi[2] - s.lo[2]);
    const double h0 = s.hi[2] - o[2], hd = -d[2];
    A -= k * k * hd * hd;
    B -= 2 * k * k * h0 * hd;
    C -= k * k * h0 * h0;
  }
  return entry(quadratic_below_zero(A, B, C, iv));
}

}  // namespace occseg::sim
