// The simulated scenes of the experiments (scene.hpp).
#include "occseg/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "occseg/error.hpp"

namespace occseg::sim {

namespace {

constexpr double kDeg = 57.29577951308232;  // degrees per radian

// Builds scenes in the paper's 6.4 x 6.4 x 2.56 m room and scales them to the requested map.
class Builder {
 public:
  Builder(const std::string& name, const Dims& dims, double vs) {
    scene_.name = name;
    scene_.frame.dims = dims;
    scene_.frame.voxel_size = vs;
    sx_ = dims.nx * vs / 6.4;
    sy_ = dims.ny * vs / 6.4;
    sz_ = dims.nz * vs / 2.56;
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
  } else {
    std::string all;
    for (const auto& n : scene_names()) all += (all.empty() ? "" : ", ") + n;
    throw Error(Status::invalid_argument, "unknown scene '" + name + "' (known: " + all + ")");
  }
}

}  // namespace

const std::vector<std::string>& scene_names() {
  static const std::vector<std::string> names = {"cone", "cube", "cylinder", "close", "table", "doorway"};
  return names;
}

Scene make_scene(const std::string& name, const Dims& dims, double voxel_size) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw Error(Status::invalid_argument, "voxel size " + std::to_string(voxel_size) + " is not positive");
  if (dims.nx < 16 || dims.ny < 16 || dims.nz < 8)
    throw Error(Status::bad_dims, "simulated maps need at least 16 x 16 x 8 voxels, got " + std::to_string(dims.nx) +
                                      " x " + std::to_string(dims.ny) + " x " + std::to_string(dims.nz));
  check_dims(dims);
  Builder b(name, dims, voxel_size);
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
