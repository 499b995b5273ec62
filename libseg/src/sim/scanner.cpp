// The simulated range sensor and its scans fused into a map (scanner.hpp).
#include "occseg/sim/scanner.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"

namespace occseg::sim {

namespace {

constexpr double kRad = 0.017453292519943295;  // radians per degree
constexpr double kAngleEps = 1e-9;             // degrees: tolerance of the field-of-view edges

// Number of steps of `step` that fit in `span` (both degrees), robust to rounding.
std::size_t steps_in(double span, double step) {
  return static_cast<std::size_t>(std::floor(span / step + 1e-9));
}

}  // namespace

const char* scan_mode_name(ScanMode m) {
  switch (m) {
    case ScanMode::planar: return "planar";
    case ScanMode::full3d: return "full3d";
    case ScanMode::rings: return "rings";
  }
  return "?";
}

void ScanConfig::validate() const {
  auto bad = [](const std::string& what) { throw Error(Status::invalid_argument, "scan config: " + what); };
  if (!(range_sigma >= 0) || !std::isfinite(range_sigma)) bad("range_sigma must be >= 0");
  if (!(angle_step_deg >= 0.01 && angle_step_deg <= 90)) bad("angle_step_deg must be in [0.01, 90]");
  if (!(ring_step_deg >= 0.01 && ring_step_deg <= 90)) bad("ring_step_deg must be in [0.01, 90]");
  if (!(max_range > 0) || !std::isfinite(max_range)) bad("max_range must be positive");
  model.validate();
}

std::vector<Vec3> ray_directions(const Viewpoint& v, ScanMode mode, double step_deg, double ring_step_deg) {
  std::size_t n_az = steps_in(v.fov_deg, step_deg) + 1;
  if (v.fov_deg >= 360) n_az = steps_in(360, step_deg);  // the last ray would repeat the first
  std::vector<double> pitches{0.0};
  if (mode != ScanMode::planar) {
    const double row = mode == ScanMode::rings ? ring_step_deg : step_deg;
    pitches.clear();
    const std::size_t n_p = steps_in(v.pitch_max_deg - v.pitch_min_deg, row) + 1;
    for (std::size_t i = 0; i < n_p; ++i) pitches.push_back(v.pitch_min_deg + i * row);
  }
  std::vector<Vec3> dirs;
  dirs.reserve(n_az * pitches.size());
  const double az0 = v.heading_deg - 0.5 * std::min(v.fov_deg, 360.0);
  for (double pitch : pitches) {
    const double cp = std::cos(pitch * kRad), sp = std::sin(pitch * kRad);
    for (std::size_t j = 0; j < n_az; ++j) {
      const double az = (az0 + j * step_deg) * kRad;
      dirs.push_back({cp * std::cos(az), cp * std::sin(az), mode == ScanMode::planar ? 0.0 : sp});
    }
  }
  return dirs;
}

bool in_view(const Viewpoint& v, ScanMode mode, const Vec3& d) {
  const double horizontal = std::hypot(d[0], d[1]);
  if (mode == ScanMode::planar) {
    if (std::abs(d[2]) > 1e-12 * (horizontal + std::abs(d[2]))) return false;
  } else {
    const double pitch = std::atan2(d[2], horizontal) / kRad;
    if (pitch < v.pitch_min_deg - kAngleEps || pitch > v.pitch_max_deg + kAngleEps) return false;
  }
  if (v.fov_deg >= 360) return true;
  if (horizontal == 0) return false;  // straight up or down: no azimuth
  const double az = std::atan2(d[1], d[0]) / kRad;
  const double diff = std::remainder(az - v.heading_deg, 360.0);
  return std::abs(diff) <= 0.5 * v.fov_deg + kAngleEps;
}

double measure_range(const Scene& scene, const Vec3& o, const Vec3& d, const ScanConfig& config, Rng& rng) {
  const double t = first_hit(scene, o, d);
  if (!(t <= config.max_range)) return std::numeric_limits<double>::quiet_NaN();
  return std::max(0.0, t + config.range_sigma * rng.gaussian());
}

std::vector<Vec3> scan_endpoints(const Scene& scene, const Vec3& sensor, const std::vector<Vec3>& directions,
                                 const ScanConfig& config, Rng& rng) {
  std::vector<Vec3> ends;
  ends.reserve(directions.size());
  for (const Vec3& d : directions) {
    double r = measure_range(scene, sensor, d, config, rng);
    if (std::isnan(r)) r = 2 * config.max_range;
    ends.push_back({sensor[0] + r * d[0], sensor[1] + r * d[1], sensor[2] + r * d[2]});
  }
  return ends;
}

Vec3 sensor_position(const Scene& scene, const Viewpoint& v, ScanMode mode, std::size_t z) {
  if (mode != ScanMode::planar) return v.position;
  const GridFrame& f = scene.frame;
  return {v.position[0], v.position[1], f.origin[2] + (static_cast<double>(z) + 0.5) * f.voxel_size};
}

Grid simulate_map(const Scene& scene, const ScanConfig& config) {
  config.validate();
  validate_scene(scene);
  SensorModel model = config.model;
  model.max_range = config.max_range;
  const GridFrame& f = scene.frame;
  Grid out(f.dims, 0.5f, f.voxel_size);
  out.origin = f.origin;

  if (config.mode != ScanMode::planar) {
    OccupancyFusion fusion(f, model);
    std::size_t k = 0;
    const double views = static_cast<double>(scene.viewpoints.size());
    if (config.progress)
      fusion.set_progress([&](std::size_t done, std::size_t count) {
        return config.progress((static_cast<double>(k) + double(done) / double(count)) / views);
      });
    for (; k < scene.viewpoints.size(); ++k) {
      const Viewpoint& v = scene.viewpoints[k];
      Rng rng(mix_seed(config.seed, 0, k));
      const Vec3 s = sensor_position(scene, v, config.mode, 0);
      const auto dirs = ray_directions(v, config.mode, config.angle_step_deg, config.ring_step_deg);
      fusion.insert_scan(s, scan_endpoints(scene, s, dirs, config, rng), config.threads);
    }
    out.p = fusion.grid().p;
    return out;
  }

  // Planar: each layer is its own 2D map (a one-voxel-thick frame), as the paper's stack of images.
  const std::size_t layer = f.dims.nx * f.dims.ny;
  std::vector<std::vector<Vec3>> dirs;
  for (const Viewpoint& v : scene.viewpoints) dirs.push_back(ray_directions(v, config.mode, config.angle_step_deg));
  std::size_t layers_done = 0;
  std::atomic<bool> stop{false};
  std::mutex report;
  parallel_for(f.dims.nz, config.threads, [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1 && !stop; ++z) {
      GridFrame lf = f;
      lf.dims.nz = 1;
      lf.origin[2] = f.origin[2] + static_cast<double>(z) * f.voxel_size;
      OccupancyFusion fusion(lf, model);
      for (std::size_t k = 0; k < scene.viewpoints.size(); ++k) {
        Rng rng(mix_seed(config.seed, z, k));
        const Vec3 s = sensor_position(scene, scene.viewpoints[k], config.mode, z);
        fusion.insert_scan(s, scan_endpoints(scene, s, dirs[k], config, rng), 1);
      }
      const Grid g = fusion.grid();
      std::copy(g.p.begin(), g.p.end(), out.p.begin() + z * layer);
      if (config.progress) {
        std::lock_guard<std::mutex> lock(report);  // one call at a time, fractions in order
        if (!stop && !config.progress(double(++layers_done) / double(f.dims.nz))) stop = true;
      }
    }
  });
  if (stop) throw Error(Status::cancelled, "simulation cancelled by the progress callback");
  return out;
}

}  // namespace occseg::sim
