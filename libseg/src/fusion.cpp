#include "occseg/fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"

namespace occseg {

namespace {
double logit(double p) { return std::log(p / (1 - p)); }
}  // namespace

void SensorModel::validate() const {
  auto in01 = [](const char* name, double v) {
    if (!(v > 0 && v < 1))
      throw Error(Status::invalid_argument, std::string("sensor model ") + name + " = " +
                                                std::to_string(v) + " is not in (0, 1)");
  };
  in01("p_hit", p_hit);
  in01("p_miss", p_miss);
  in01("clamp_min", clamp_min);
  in01("clamp_max", clamp_max);
  if (p_hit <= 0.5) throw Error(Status::invalid_argument, "sensor model p_hit must be above 0.5");
  if (p_miss >= 0.5) throw Error(Status::invalid_argument, "sensor model p_miss must be below 0.5");
  if (clamp_min >= 0.5 || clamp_max <= 0.5)
    throw Error(Status::invalid_argument, "sensor model clamping must bracket 0.5");
  if (std::isnan(max_range)) throw Error(Status::invalid_argument, "sensor model max_range is NaN");
}

OccupancyFusion::OccupancyFusion(const GridFrame& frame, const SensorModel& model)
    : frame_(frame), model_(model) {
  check_dims(frame.dims);
  model.validate();
  if (!(frame.voxel_size > 0) || !std::isfinite(frame.voxel_size))
    throw Error(Status::bad_value, "voxel size " + std::to_string(frame.voxel_size) + " is not positive");
  for (double o : frame.origin)
    if (!std::isfinite(o)) throw Error(Status::bad_value, "grid origin is not finite");
  l_hit_ = static_cast<float>(logit(model.p_hit));
  l_miss_ = static_cast<float>(logit(model.p_miss));
  l_min_ = static_cast<float>(logit(model.clamp_min));
  l_max_ = static_cast<float>(logit(model.clamp_max));
  log_odds_.assign(frame.dims.count(), 0.0f);
  marks_.assign(frame.dims.count(), 0);
}

// Amanatides & Woo voxel traversal of the segment from -> to (world metres), clipped to the
// grid box. Marks every crossed voxel as a miss and the endpoint voxel as a hit when `hit`.
void OccupancyFusion::trace(const Vec3& from, const Vec3& to, bool hit) {
  const double n[3] = {double(frame_.dims.nx), double(frame_.dims.ny), double(frame_.dims.nz)};
  double a[3], b[3], d[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = (from[k] - frame_.origin[k]) / frame_.voxel_size;
    b[k] = (to[k] - frame_.origin[k]) / frame_.voxel_size;
    d[k] = b[k] - a[k];
  }
  // Clip the parameter range [t0, t1] of a + t d to the box [0, n] (slab method).
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (a[k] < 0 || a[k] >= n[k]) return;
      continue;
    }
    double ta = (0 - a[k]) / d[k], tb = (n[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return;
  const bool end_inside = hit && t1 >= 1.0;
  const std::size_t nx = frame_.dims.nx, nxy = nx * frame_.dims.ny;
  long c[3], last[3];
  int step[3];
  double tmax[3], tdelta[3];
  for (int k = 0; k < 3; ++k) {
    const double p = a[k] + t0 * d[k];
    c[k] = std::clamp(static_cast<long>(std::floor(p)), 0L, static_cast<long>(n[k]) - 1);
    const double q = a[k] + t1 * d[k];
    last[k] = std::clamp(static_cast<long>(std::floor(q)), 0L, static_cast<long>(n[k]) - 1);
    if (d[k] > 0) {
      step[k] = 1;
      tmax[k] = (c[k] + 1 - a[k]) / d[k];
      tdelta[k] = 1 / d[k];
    } else if (d[k] < 0) {
      step[k] = -1;
      tmax[k] = (c[k] - a[k]) / d[k];
      tdelta[k] = -1 / d[k];
    } else {
      step[k] = 0;
      tmax[k] = tdelta[k] = std::numeric_limits<double>::infinity();
    }
  }
  // Bounded walk: at most the number of voxel faces crossed plus one.
  long budget = std::labs(last[0] - c[0]) + std::labs(last[1] - c[1]) + std::labs(last[2] - c[2]) + 1;
  for (; budget > 0; --budget) {
    const std::size_t i = static_cast<std::size_t>(c[0]) + nx * static_cast<std::size_t>(c[1]) +
                          nxy * static_cast<std::size_t>(c[2]);
    const bool at_end = c[0] == last[0] && c[1] == last[1] && c[2] == last[2];
    __atomic_fetch_or(&marks_[i], static_cast<std::uint8_t>(at_end && end_inside ? 2 : 1), __ATOMIC_RELAXED);
    if (at_end) break;
    int k = tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2);
    c[k] += step[k];
    tmax[k] += tdelta[k];
    if (c[k] < 0 || c[k] >= static_cast<long>(n[k])) break;
  }
}

void OccupancyFusion::insert_scan(const Vec3& sensor, const float* xyz, std::size_t count,
                                  std::size_t stride, int threads) {
  for (double s : sensor)
    if (!std::isfinite(s)) throw Error(Status::bad_value, "sensor origin is not finite");
  std::fill(marks_.begin(), marks_.end(), 0);
  const double maxr = model_.max_range;
  std::uint64_t used = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = xyz + i * stride;
    used += std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
  }
  auto cast = [&](std::size_t i) {
    const float* p = xyz + i * stride;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return;
    Vec3 end{p[0], p[1], p[2]};
    bool hit = true;
    if (maxr >= 0) {
      const double dx = end[0] - sensor[0], dy = end[1] - sensor[1], dz = end[2] - sensor[2];
      const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (len > maxr) {  // a max-range return marks free space only
        const double s = maxr / len;
        end = {sensor[0] + dx * s, sensor[1] + dy * s, sensor[2] + dz * s};
        hit = false;
      }
    }
    trace(sensor, end, hit);
  };
  // With a progress callback rays go in chunks, so long scans report; marks are ORed, so the
  // chunking changes nothing in the result.
  const std::size_t chunk = progress_ ? std::size_t(1) << 16 : std::max<std::size_t>(count, 1);
  for (std::size_t c0 = 0; c0 < count; c0 += chunk) {
    const std::size_t c1 = std::min(count, c0 + chunk);
    parallel_for(c1 - c0, threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = c0 + b; i < c0 + e; ++i) cast(i);
    });
    if (progress_ && !progress_(c1, count))
      throw Error(Status::cancelled, "ray casting cancelled by the progress callback");
  }
  const float lh = l_hit_, lm = l_miss_, lo = l_min_, hi = l_max_;
  parallel_for(marks_.size(), threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::uint8_t m = marks_[i];
      if (!m) continue;
      log_odds_[i] = std::clamp(log_odds_[i] + ((m & 2) ? lh : lm), lo, hi);
    }
  });
  ++scans_;
  rays_ += used;
}

void OccupancyFusion::insert_scan(const Vec3& sensor, const std::vector<Vec3>& endpoints, int threads) {
  std::vector<float> xyz(endpoints.size() * 3);
  for (std::size_t i = 0; i < endpoints.size(); ++i)
    for (int k = 0; k < 3; ++k) xyz[3 * i + k] = static_cast<float>(endpoints[i][k]);
  insert_scan(sensor, xyz.data(), endpoints.size(), 3, threads);
}

Grid OccupancyFusion::grid() const {
  Grid g;
  g.dims = frame_.dims;
  g.voxel_size = frame_.voxel_size;
  g.origin = frame_.origin;
  g.p.resize(log_odds_.size());
  for (std::size_t i = 0; i < log_odds_.size(); ++i) {
    const float l = log_odds_[i];
    g.p[i] = l == 0.0f ? 0.5f : static_cast<float>(1.0 / (1.0 + std::exp(-static_cast<double>(l))));
  }
  return g;
}

GridFrame fit_frame(const std::vector<Vec3>& points, double voxel_size, double margin) {
  if (!(voxel_size > 0)) throw Error(Status::bad_value, "voxel size must be positive");
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi{-lo[0], -lo[1], -lo[2]};
  std::size_t used = 0;
  for (const Vec3& p : points) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    ++used;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  }
  if (!used) throw Error(Status::bad_value, "no finite point to fit a grid to");
  GridFrame f;
  f.voxel_size = voxel_size;
  std::size_t n[3];
  for (int k = 0; k < 3; ++k) {
    const double a = std::floor((lo[k] - margin) / voxel_size), b = std::floor((hi[k] + margin) / voxel_size) + 1;
    if (!(b - a <= double(kMaxVoxels)))
      throw Error(Status::bad_dims, "points span " + std::to_string((b - a) * voxel_size) +
                                        " m: too many voxels of " + std::to_string(voxel_size) + " m");
    f.origin[k] = a * voxel_size;
    n[k] = static_cast<std::size_t>(b - a);
  }
  f.dims = Dims{n[0], n[1], n[2]};
  check_dims(f.dims);
  return f;
}

}  // namespace occseg
