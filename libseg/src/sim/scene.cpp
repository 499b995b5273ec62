// The simulated scenes of the experiments (scene.hpp).
#include "occseg/sim/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "occseg/error.hpp"

namespace occseg::sim {

namespace {

constexpr double kDeg = 57.29577951308232;  // degrees per radian

// Builds scenes in a room of `room` metres (the paper's 6.4 x 6.4 x 2.56 m unless a scene says
// otherwise) and scales them to the requested map.
class Builder {
 public:
  Builder(const std::string& name, const Dims& dims, double vs, const Vec3& room = {6.4, 6.4, 2.56}) {
    scene_.name = name;
    scene_.frame.dims = dims;
    scene_.frame.voxel_size = vs;
    sx_ = dims.nx * vs / room[0];
    sy_ = dims.ny * vs / room[1];
    sz_ = dims.nz * vs / room[2];
    s_ = std::min(sx_, sy_);
  }
  double X(double x) const { return x * sx_; }
  double Y(double y) const { return y * sy_; }
  double Z(double z) const { return z * sz_; }
  double R(double r) const { return r * s_; }
  double vs() const { return scene_.frame.voxel_size; }

  std::uint16_t object(const std::string& name) {
    scene_.objects.push_back(name);
    return static_cast<std::uint16_t>(scene_.objects.size());
  }
  void add(const Shape& s) { scene_.shapes.push_back(s); }
  // A sensor at (x, y) (room metres) looking at (tx, ty); 3D scans take it at height z.
  void view_at(double x, double y, double tx, double ty, double z = 1.2) {
    Viewpoint v;
    v.position = {X(x), Y(y), Z(z)};
    v.heading_deg = std::atan2(Y(ty) - Y(y), X(tx) - X(x)) * kDeg;
    scene_.viewpoints.push_back(v);
  }
  // A sensor at (x, y, z) (room metres) seeing all around, as a spinning 3D lidar.
  void view_all_around(double x, double y, double z) {
    Viewpoint v;
    v.position = {X(x), Y(y), Z(z)};
    v.fov_deg = 360;
    scene_.viewpoints.push_back(v);
  }
  // A sensor at `dist` metres from (cx, cy) in direction `angle_deg`, looking at (cx, cy).
  void view_around(double cx, double cy, double dist, double angle_deg) {
    const double a = angle_deg / kDeg;
    view_at(cx + dist * std::cos(a), cy + dist * std::sin(a), cx, cy);
  }
  void slice(int axis, double metres) {
    const std::size_t n[3] = {scene_.frame.dims.nx, scene_.frame.dims.ny, scene_.frame.dims.nz};
    const double scaled = axis == 0 ? X(metres) : axis == 1 ? Y(metres) : Z(metres);
    const double i = std::floor(scaled / vs());
    scene_.slices.push_back({axis, static_cast<std::size_t>(std::clamp(i, 0.0, double(n[axis] - 1)))});
  }
  Scene take() { return std::move(scene_); }

 private:
  Scene scene_;
  double sx_, sy_, sz_, s_;
};

// A box of room metres [x0, x1] x [y0, y1] x [z0, z1], each extent at least `min_m` metres after
// scaling, grown about its centre (walls, slabs and table tops never thinner than 2 voxels).
void add_box_min(Builder& b, double x0, double y0, double z0, double x1, double y1, double z1, double min_m,
                 std::uint16_t id) {
  double lo[3] = {b.X(x0), b.Y(y0), b.Z(z0)}, hi[3] = {b.X(x1), b.Y(y1), b.Z(z1)};
  for (int k = 0; k < 3; ++k)
    if (hi[k] - lo[k] < min_m) {
      const double c = 0.5 * (lo[k] + hi[k]);
      lo[k] = c - 0.5 * min_m;
      hi[k] = c + 0.5 * min_m;
    }
  b.add(make_box({lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, id));
}

// A wall of the building along x (axis 0, at y = at) or along y (axis 1, at x = at), from `from`
// to `to` (room metres, 20 cm thick, floor to ceiling), with doorways of 0.9 x 2.1 m centred at
// `doors`: one box on each side of every doorway and a lintel above it.
void add_wall(Builder& b, int axis, double at, double from, double to, const std::vector<double>& doors,
              double floor_top, double ceiling, std::uint16_t id) {
  const double t = 0.1, min_t = 2 * b.vs();
  auto piece = [&](double a0, double a1, double z0, double z1) {
    if (a1 <= a0 || z1 <= z0) return;
    if (axis == 0) add_box_min(b, a0, at - t, z0, a1, at + t, z1, min_t, id);
    else add_box_min(b, at - t, a0, z0, at + t, a1, z1, min_t, id);
  };
  double start = from;
  for (double c : doors) {
    piece(start, c - 0.45, floor_top, ceiling);
    piece(c - 0.45, c + 0.45, floor_top + 2.1, ceiling);
    start = c + 0.45;
  }
  piece(start, to, floor_top, ceiling);
}

// A table of room metres [x0, x1] x [y0, y1], top 0.75 m above the floor (4 cm thick), four legs 6 cm across.
void add_table(Builder& b, double x0, double y0, double x1, double y1, std::uint16_t id) {
  const double top = std::max(b.Z(0.04), 2 * b.vs()), leg_r = std::max(b.R(0.03), 1.5 * b.vs());
  const double z1 = b.Z(0.85), z0 = z1 - top, floor = b.Z(0.1);  // on the 10 cm floor slab
  b.add(make_box({b.X(x0), b.Y(y0), z0}, {b.X(x1), b.Y(y1), z1}, id));
  const double in = leg_r + b.R(0.05);
  for (double lx : {b.X(x0) + in, b.X(x1) - in})
    for (double ly : {b.Y(y0) + in, b.Y(y1) - in}) b.add(make_cylinder(lx, ly, floor, z0, leg_r, id));
}

// One storey of an office building, 20 x 15 x 3 m at the scale 1 (400 x 300 x 60 voxels of 5 cm):
// floor and ceiling slabs (10 cm), outer walls, a corridor along x with three rooms south of it
// and two north, 20 cm walls with doorways, furniture standing free (tables, boxes, a cabinet, a
// column) and one cabinet flush against a wall. The shell (slabs and walls, one connected solid)
// is one object, every piece of furniture another. Seven spinning 3D lidars, one per room and
// two in the corridor, 1.2 m above the floor slab.
void build_building(Builder& b) {
  const auto shell = b.object("shell (floor, ceiling, walls)");
  const double slab = 2 * b.vs(), fl = 0.1, ce = 2.9;  // floor top, ceiling underside (room metres)
  add_box_min(b, 0, 0, 0, 20, 15, fl, slab, shell);
  add_box_min(b, 0, 0, ce, 20, 15, 3.0, slab, shell);
  add_wall(b, 0, 0.1, 0, 20, {}, fl, ce, shell);    // south
  add_wall(b, 0, 14.9, 0, 20, {}, fl, ce, shell);   // north
  add_wall(b, 1, 0.1, 0.2, 14.8, {}, fl, ce, shell);   // west
  add_wall(b, 1, 19.9, 0.2, 14.8, {}, fl, ce, shell);  // east
  add_wall(b, 0, 6.5, 0.2, 19.8, {3.5, 10.0, 16.5}, fl, ce, shell);  // corridor, south side
  add_wall(b, 0, 8.5, 0.2, 19.8, {5.0, 15.0}, fl, ce, shell);        // corridor, north side
  add_wall(b, 1, 7.0, 0.2, 6.4, {}, fl, ce, shell);    // between the south rooms
  add_wall(b, 1, 13.0, 0.2, 6.4, {}, fl, ce, shell);
  add_wall(b, 1, 10.0, 8.6, 14.8, {}, fl, ce, shell);  // between the north rooms

  add_table(b, 1.5, 2.0, 3.3, 2.9, b.object("table, room 1"));
  add_box_min(b, 4.5, 1.0, fl, 5.3, 1.8, fl + 0.8, 2 * b.vs(), b.object("box, room 1"));
  add_table(b, 8.5, 2.5, 10.5, 3.5, b.object("table, room 2"));
  add_box_min(b, 11.0, 4.5, fl, 11.6, 5.1, fl + 0.5, 2 * b.vs(), b.object("box, room 2"));
  add_box_min(b, 15.0, 0.2, fl, 16.2, 0.7, fl + 1.9, 2 * b.vs(), b.object("cabinet against the wall, room 3"));
  add_box_min(b, 17.0, 3.0, fl, 17.6, 3.6, fl + 1.2, 2 * b.vs(), b.object("cabinet, room 3"));
  add_table(b, 3.0, 11.0, 5.0, 12.2, b.object("table, room 4"));
  add_box_min(b, 7.5, 12.5, fl, 8.3, 13.3, fl + 0.7, 2 * b.vs(), b.object("box, room 4"));
  {
    const auto column = b.object("column, room 5");
    b.add(make_cylinder(b.X(14.0), b.Y(11.5), b.Z(fl), b.Z(ce), std::max(b.R(0.25), 2 * b.vs()), column));
  }
  add_table(b, 16.0, 12.0, 18.0, 13.2, b.object("table, room 5"));

  for (const auto& p : std::vector<std::array<double, 2>>{{4.0, 4.0}, {10.0, 1.5}, {16.5, 2.0}, {6.5, 10.5},
                                                         {12.0, 13.0}, {3.0, 7.5}, {14.0, 7.5}})
    b.view_all_around(p[0], p[1], fl + 1.2);
  b.slice(2, 0.5);
  b.slice(2, 2.0);
  b.slice(1, 3.0);
}

void build(Builder& b, const std::string& name) {
  if (name == "cone") {
    const auto id = b.object("cone");
    b.add(make_cone(b.X(3.2), b.Y(3.2), 0, b.Z(2.2), b.R(1.2), id));
    b.view_around(3.2, 3.2, 2.6, 225);
    b.view_around(3.2, 3.2, 2.6, 150);
    b.slice(2, 0.3);
    b.slice(2, 1.2);
    b.slice(1, 3.2);
  } else if (name == "cube") {
    const auto id = b.object("cube");
    b.add(make_box({b.X(2.4), b.Y(2.4), 0}, {b.X(4.0), b.Y(4.0), b.Z(1.6)}, id));
    for (double a : {200.0, 260.0, 330.0}) b.view_around(3.2, 3.2, 2.6, a);
    b.slice(2, 0.4);
    b.slice(2, 1.2);
    b.slice(1, 3.2);
  } else if (name == "cylinder") {
    const auto id = b.object("cylinder");
    b.add(make_cylinder(b.X(3.2), b.Y(3.2), 0, b.Z(2.0), b.R(0.8), id));
    for (double a : {45.0, 135.0, 225.0, 315.0}) b.view_around(3.2, 3.2, 2.6, a);
    b.slice(2, 0.5);
    b.slice(2, 1.5);
    b.slice(1, 3.2);
  } else if (name == "close") {
    // A box and a cylinder 12 cm (6 voxels) apart; two sensors look straight through the gap.
    const auto box = b.object("box"), cyl = b.object("cylinder");
    b.add(make_box({b.X(1.9), b.Y(2.6), 0}, {b.X(3.1), b.Y(3.8), b.Z(1.2)}, box));
    b.add(make_cylinder(b.X(3.1) + b.R(0.12) + b.R(0.6), b.Y(3.2), 0, b.Z(1.6), b.R(0.6), cyl));
    const double gap_x = (b.X(3.1) + 0.5 * b.R(0.12)) / b.X(1.0);
    b.view_at(gap_x, 0.5, gap_x, 3.2);
    b.view_at(gap_x, 5.9, gap_x, 3.2);
    b.view_at(0.6, 1.0, 3.2, 3.2);
    b.slice(2, 0.5);
    b.slice(2, 1.4);
    b.slice(1, 3.2);
  } else if (name == "table") {
    // A 4 cm top on four 6 cm legs: thin structures, never thinner than 2 voxels.
    const auto id = b.object("table");
    const double top = std::max(b.Z(0.04), 2 * b.vs()), leg_r = std::max(b.R(0.03), 1.5 * b.vs());
    const double z1 = b.Z(0.76), z0 = z1 - top;
    const double x0 = b.X(2.4), x1 = b.X(4.0), y0 = b.Y(2.75), y1 = b.Y(3.65);
    b.add(make_box({x0, y0, z0}, {x1, y1, z1}, id));
    const double in = leg_r + b.R(0.05);
    for (double lx : {x0 + in, x1 - in})
      for (double ly : {y0 + in, y1 - in}) b.add(make_cylinder(lx, ly, 0, z0, leg_r, id));
    for (double a : {200.0, 270.0, 20.0}) b.view_around(3.2, 3.2, 2.6, a);
    b.slice(2, 0.75);
    b.slice(2, 0.4);
    b.slice(1, 2.83);
  } else if (name == "doorway") {
    // A 20 cm wall across the room with a 0.9 x 2.0 m doorway; a box behind it, seen only
    // through the doorway. All sensors are on the near side.
    const auto wall = b.object("wall"), box = b.object("box");
    const double H = b.Z(2.56), wx0 = b.X(3.6), wx1 = b.X(3.8);
    const double d0 = b.Y(2.75), d1 = b.Y(3.65), dh = b.Z(2.0);
    b.add(make_box({wx0, 0, 0}, {wx1, d0, H}, wall));
    b.add(make_box({wx0, d1, 0}, {wx1, b.Y(6.4), H}, wall));
    b.add(make_box({wx0, d0, dh}, {wx1, d1, H}, wall));
    b.add(make_box({b.X(4.8), b.Y(3.0), 0}, {b.X(5.4), b.Y(3.6), b.Z(0.8)}, box));
    b.view_at(1.0, 3.2, 3.7, 3.2);
    b.view_at(0.8, 1.2, 3.7, 3.2);
    b.view_at(0.8, 5.2, 3.7, 3.2);
    b.slice(2, 0.5);
    b.slice(2, 2.2);
    b.slice(1, 3.3);
  } else if (name == "building") {
    build_building(b);
  } else {
    std::string all;
    for (const auto& n : scene_names()) all += (all.empty() ? "" : ", ") + n;
    throw Error(Status::invalid_argument, "unknown scene '" + name + "' (known: " + all + ")");
  }
}

}  // namespace

const std::vector<std::string>& scene_names() {
  static const std::vector<std::string> names = {"cone",  "cube",    "cylinder",
                                                   "close", "table",   "doorway", "building"};
  return names;
}

Scene make_scene(const std::string& name, const Dims& dims, double voxel_size) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw Error(Status::invalid_argument, "voxel size " + std::to_string(voxel_size) + " is not positive");
  if (dims.nx < 16 || dims.ny < 16 || dims.nz < 8)
    throw Error(Status::bad_dims, "simulated maps need at least 16 x 16 x 8 voxels, got " + std::to_string(dims.nx) +
                                      " x " + std::to_string(dims.ny) + " x " + std::to_string(dims.nz));
  check_dims(dims);
  Builder b = name == "building" ? Builder(name, dims, voxel_size, {20.0, 15.0, 3.0}) : Builder(name, dims, voxel_size);
  build(b, name);
  Scene s = b.take();
  validate_scene(s);
  return s;
}

double first_hit(const Scene& scene, const Vec3& o, const Vec3& d, std::uint16_t* object) {
  double best = std::numeric_limits<double>::infinity();
  std::uint16_t id = 0;
  for (const Shape& s : scene.shapes) {
    const double t = intersect(s, o, d);
    if (t < best) {
      best = t;
      id = s.object;
    }
  }
  if (object) *object = id;
  return best;
}

void validate_scene(const Scene& scene) {
  if (scene.viewpoints.empty()) throw Error(Status::invalid_argument, "scene '" + scene.name + "' has no viewpoint");
  for (const Shape& s : scene.shapes)
    if (s.object == 0 || s.object > scene.objects.size())
      throw Error(Status::invalid_argument, "scene '" + scene.name + "': shape with object id " +
                                                std::to_string(s.object) + " has no object name");
  for (const Viewpoint& v : scene.viewpoints) {
    if (!(v.fov_deg > 0 && v.fov_deg <= 360))
      throw Error(Status::invalid_argument, "viewpoint field of view " + std::to_string(v.fov_deg) +
                                                " is not in (0, 360] degrees");
    if (!(v.pitch_min_deg >= -90 && v.pitch_min_deg <= v.pitch_max_deg && v.pitch_max_deg <= 90))
      throw Error(Status::invalid_argument, "viewpoint pitch range is not within [-90, 90] degrees");
  }
}

}  // namespace occseg::sim
