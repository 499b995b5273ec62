// The ground truth of a simulated scene (truth.hpp).
#include "occseg/sim/truth.hpp"

#include <cmath>
#include <limits>

#include "occseg/params.hpp"
#include "occseg/parallel.hpp"

namespace occseg::sim {

namespace {

Vec3 voxel_point(const GridFrame& f, double x, double y, double z) {
  return {f.origin[0] + x * f.voxel_size, f.origin[1] + y * f.voxel_size, f.origin[2] + z * f.voxel_size};
}

bool inside_any(const Scene& scene, const Vec3& p) {
  for (const Shape& s : scene.shapes)
    if (contains(s, p)) return true;
  return false;
}

// For each voxel: may a solid's surface cross it? True when its centre and 8 corners are not
// all on the same side (inside any solid or not).
std::vector<std::uint8_t> surface_voxels(const Scene& scene, int threads) {
  const GridFrame& f = scene.frame;
  const std::size_t nx = f.dims.nx, ny = f.dims.ny, nz = f.dims.nz;
  const std::size_t cx = nx + 1, cy = ny + 1;
  std::vector<std::uint8_t> corner(cx * cy * (nz + 1));
  parallel_for(nz + 1, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y <= ny; ++y)
        for (std::size_t x = 0; x <= nx; ++x)
          corner[x + cx * (y + cy * z)] = inside_any(scene, voxel_point(f, double(x), double(y), double(z)));
  });
  std::vector<std::uint8_t> out(f.dims.count());
  parallel_for(nz, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x) {
          const std::uint8_t c = inside_any(scene, voxel_point(f, x + 0.5, y + 0.5, z + 0.5));
          bool mixed = false;
          for (int k = 0; k < 8 && !mixed; ++k)
            mixed = corner[(x + (k & 1)) + cx * ((y + ((k >> 1) & 1)) + cy * (z + (k >> 2)))] != c;
          out[x + nx * (y + ny * z)] = mixed;
        }
  });
  return out;
}

// first_hit(scene, o, d) <= t_max, stopping at the first solid met within t_max.
bool hit_within(const Scene& scene, const Vec3& o, const Vec3& d, double t_max) {
  for (const Shape& s : scene.shapes)
    if (intersect(s, o, d) <= t_max) return true;
  return false;
}

// Whether the first solid met by the ray o + t d lies within max_range and inside the box
// [bl, bh]: first_hit, then the point o + t d tested against the box. The solids are scanned as
// first_hit does, but the scan stops once a solid is met before the box along an axis on which
// the ray moves towards it: the first hit's t is no larger, and o_k + t d_k is monotonic in t in
// floating point too, so that point lies before the box as well and the answer is the same.
bool first_hit_in_box(const Scene& scene, const Vec3& o, const Vec3& d, const Vec3& bl, const Vec3& bh,
                      double max_range) {
  double best = std::numeric_limits<double>::infinity();
  for (const Shape& s : scene.shapes) {
    const double t = intersect(s, o, d);
    if (!(t < best)) continue;
    best = t;
    for (int k = 0; k < 3; ++k) {
      const double h = o[k] + t * d[k];
      if ((d[k] > 0 && h < bl[k]) || (d[k] < 0 && h > bh[k])) return false;
    }
  }
  if (!(best <= max_range)) return false;
  for (int k = 0; k < 3; ++k) {
    const double h = o[k] + best * d[k];
    if (!(h >= bl[k] && h <= bh[k])) return false;
  }
  return true;
}

}  // namespace

std::vector<std::uint16_t> object_mask(const Scene& scene, int threads) {
  const GridFrame& f = scene.frame;
  const std::size_t nx = f.dims.nx, ny = f.dims.ny;
  std::vector<std::uint16_t> mask(f.dims.count(), 0);
  parallel_for(f.dims.nz, threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x) {
          const Vec3 c = voxel_point(f, x + 0.5, y + 0.5, z + 0.5);
          for (const Shape& s : scene.shapes)
            if (contains(s, c)) {
              mask[x + nx * (y + ny * z)] = s.object;
              break;
            }
        }
  });
  return mask;
}

Truth ground_truth(const Scene& scene, const ScanConfig& config) {
  config.validate();
  validate_scene(scene);
  const GridFrame& f = scene.frame;
  const std::size_t nx = f.dims.nx, ny = f.dims.ny;
  const double vs = f.voxel_size;
  Truth t;
  t.dims = f.dims;
  t.objects = object_mask(scene, config.threads);
  const std::vector<std::uint8_t> surface = surface_voxels(scene, config.threads);
  t.state.assign(f.dims.count(), static_cast<std::uint8_t>(State::unknown));

  // Aim points within a voxel, as offsets from its centre in voxels.
  std::vector<Vec3> aims;
  const int zr = config.mode == ScanMode::planar ? 0 : 1;
  for (int dz = -zr; dz <= zr; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) aims.push_back({dx / 3.0, dy / 3.0, dz / 3.0});

  parallel_for(f.dims.nz, config.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z) {
      std::vector<Vec3> sensors;
      for (const Viewpoint& v : scene.viewpoints) sensors.push_back(sensor_position(scene, v, config.mode, z));
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x) {
          const std::size_t i = x + nx * (y + ny * z);
          const Vec3 lo = voxel_point(f, double(x), double(y), double(z));
          // Same arithmetic as sensor_position, so a planar sensor and its layer's centres agree in z.
          const Vec3 c = voxel_point(f, x + 0.5, y + 0.5, z + 0.5);
          // The voxel's box, a hair wider (a hit on its face counts).
          const double eps = 1e-9 * vs;
          const Vec3 bl = {lo[0] - eps, lo[1] - eps, lo[2] - eps};
          const Vec3 bh = {lo[0] + vs + eps, lo[1] + vs + eps, lo[2] + vs + eps};
          bool occupied = false, free = false;
          // Only a voxel the surface may cross can become occupied; others stop once seen free.
          for (std::size_t k = 0; k < sensors.size() && !occupied && !(free && !surface[i]); ++k) {
            const Viewpoint& v = scene.viewpoints[k];
            const Vec3& s = sensors[k];
            if (surface[i]) {
              for (const Vec3& a : aims) {
                const Vec3 p = {c[0] + a[0] * vs, c[1] + a[1] * vs, c[2] + a[2] * vs};
                Vec3 d = {p[0] - s[0], p[1] - s[1], p[2] - s[2]};
                const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                if (len == 0) continue;
                for (double& e : d) e /= len;
                if (!in_view(v, config.mode, d)) continue;
                if (first_hit_in_box(scene, s, d, bl, bh, config.max_range)) {
                  occupied = true;
                  break;
                }
              }
            }
            if (free || occupied || t.objects[i] != 0) continue;
            Vec3 d = {c[0] - s[0], c[1] - s[1], c[2] - s[2]};
            const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (len > config.max_range) continue;
            if (len <= 1e-9 * vs) {  // the sensor's own voxel
              free = true;
              continue;
            }
            for (double& e : d) e /= len;
            if (!in_view(v, config.mode, d)) continue;
            free = !hit_within(scene, s, d, len);
          }
          t.state[i] = static_cast<std::uint8_t>(occupied ? State::occupied : free ? State::free : State::unknown);
        }
    }
  });
  return t;
}

}  // namespace occseg::sim
