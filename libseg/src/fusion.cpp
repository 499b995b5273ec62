#include "occseg/fusion.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

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

namespace {

// Voxels a scan may have marked: per axis, the range between the first and the last cell of
// every walk (walks are monotone along each axis). The apply pass only visits this box.
struct TouchBox {
  long lo[3] = {std::numeric_limits<long>::max(), std::numeric_limits<long>::max(),
                std::numeric_limits<long>::max()};
  long hi[3] = {-1, -1, -1};
  void add(const long* c) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], c[k]);
      hi[k] = std::max(hi[k], c[k]);
    }
  }
  void merge(const TouchBox& o) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], o.lo[k]);
      hi[k] = std::max(hi[k], o.hi[k]);
    }
  }
  bool empty() const { return hi[0] < lo[0]; }
};

// Marks one voxel. Reading first skips the locked read-modify-write when the mark is already
// there (most voxels near the sensor are crossed by many rays) and keeps the cache line shared
// between threads. A miss is dropped on any marked voxel: the apply pass only asks "marked?"
// and "hit?", so a miss adds nothing to a voxel that is already marked.
inline void mark(std::uint8_t* m, std::uint8_t bit) {
  const std::uint8_t v = __atomic_load_n(m, __ATOMIC_RELAXED);
  if (bit == 1 ? v == 0 : !(v & 2)) __atomic_fetch_or(m, bit, __ATOMIC_RELAXED);
}

// Amanatides & Woo voxel traversal of the segment a -> b (grid units: (world - origin) /
// voxel_size), clipped to the grid box. Marks every crossed voxel as a miss and the endpoint
// voxel as a hit when `hit`. The floating-point arithmetic (clipping, tmax, tdelta, the axis
// choice) is exactly that of the first implementation, so the same voxels are visited; what
// changed is the bookkeeping: the linear index advances by a stride instead of being recomputed,
// the end test compares one index, and the axis choice is branch-free.
void trace(const double* a, const double* b, bool hit, const Dims& dims, std::uint8_t* marks, TouchBox& box) {
  const double n[3] = {double(dims.nx), double(dims.ny), double(dims.nz)};
  double d[3];
  for (int k = 0; k < 3; ++k) d[k] = b[k] - a[k];
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
  const std::size_t nx = dims.nx, nxy = nx * dims.ny;
  long c[3], last[3], step[3];
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
  box.add(c);
  // Bounded walk: at most the number of voxel faces crossed plus one.
  long budget = std::labs(last[0] - c[0]) + std::labs(last[1] - c[1]) + std::labs(last[2] - c[2]) + 1;
  std::size_t i = static_cast<std::size_t>(c[0]) + nx * static_cast<std::size_t>(c[1]) +
                  nxy * static_cast<std::size_t>(c[2]);
  const std::size_t end = static_cast<std::size_t>(last[0]) + nx * static_cast<std::size_t>(last[1]) +
                          nxy * static_cast<std::size_t>(last[2]);
  // Unsigned wrap-around makes a step of -1 subtract the stride.
  const std::size_t sx = static_cast<std::size_t>(step[0]), sy = static_cast<std::size_t>(step[1]) * nx,
                    sz = static_cast<std::size_t>(step[2]) * nxy;
  double tx = tmax[0], ty = tmax[1], tz = tmax[2];
  const double dx = tdelta[0], dy = tdelta[1], dz = tdelta[2];
  long cx = c[0], cy = c[1], cz = c[2];
  for (; budget > 0; --budget) {
    if (i == end) {
      mark(marks + i, end_inside ? 2 : 1);
      break;
    }
    mark(marks + i, 1);
    // Same choice as tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2).
    const bool xy = tx < ty, xz = tx < tz, yz = ty < tz;
    const bool kx = xy && xz, ky = !xy && yz, kz = !kx && !ky;
    cx += kx ? step[0] : 0;
    cy += ky ? step[1] : 0;
    cz += kz ? step[2] : 0;
    // Adding 0.0 leaves every tmax unchanged (finite, or +inf on an axis the ray never takes).
    tx += kx ? dx : 0.0;
    ty += ky ? dy : 0.0;
    tz += kz ? dz : 0.0;
    i += kx ? sx : (ky ? sy : sz);
    if ((static_cast<std::size_t>(cx) >= dims.nx) | (static_cast<std::size_t>(cy) >= dims.ny) |
        (static_cast<std::size_t>(cz) >= dims.nz))
      break;
  }
  // The walk went no further than (cx, cy, cz) on any axis; a step out of the grid was not taken.
  const long fin[3] = {std::clamp(cx, 0L, long(dims.nx) - 1), std::clamp(cy, 0L, long(dims.ny) - 1),
                       std::clamp(cz, 0L, long(dims.nz) - 1)};
  box.add(fin);
}

// Calls fn(row start index, x0, x1) for every x-row of the box, rows spread over threads.
template <typename Fn>
void for_box_rows(const TouchBox& box, const Dims& dims, int threads, Fn&& fn) {
  if (box.empty()) return;
  const std::size_t ny = static_cast<std::size_t>(box.hi[1] - box.lo[1] + 1);
  const std::size_t rows = ny * static_cast<std::size_t>(box.hi[2] - box.lo[2] + 1);
  const std::size_t x0 = static_cast<std::size_t>(box.lo[0]), x1 = static_cast<std::size_t>(box.hi[0]) + 1;
  parallel_for(rows, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) {
      const std::size_t y = static_cast<std::size_t>(box.lo[1]) + r % ny;
      const std::size_t z = static_cast<std::size_t>(box.lo[2]) + r / ny;
      fn((z * dims.ny + y) * dims.nx, x0, x1);
    }
  });
}

}  // namespace

void OccupancyFusion::insert_scan(const Vec3& sensor, const float* xyz, std::size_t count,
                                  std::size_t stride, int threads) {
  for (double s : sensor)
    if (!std::isfinite(s)) throw Error(Status::bad_value, "sensor origin is not finite");
  // marks_ is all zero between scans: the apply pass (or a cancel) clears what a scan set.
  const double maxr = model_.max_range;
  std::uint64_t used = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = xyz + i * stride;
    used += std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
  }
  const double vs = frame_.voxel_size;
  const double a[3] = {(sensor[0] - frame_.origin[0]) / vs, (sensor[1] - frame_.origin[1]) / vs,
                       (sensor[2] - frame_.origin[2]) / vs};
  std::uint8_t* marks = marks_.data();
  auto cast = [&](std::size_t i, TouchBox& box) {
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
    double b[3];
    for (int k = 0; k < 3; ++k) b[k] = (end[k] - frame_.origin[k]) / vs;
    trace(a, b, hit, frame_.dims, marks, box);
  };
  TouchBox box;
  std::mutex box_mutex;
  // With a progress callback rays go in chunks, so long scans report; marks are ORed, so the
  // chunking changes nothing in the result.
  const std::size_t chunk = progress_ ? std::size_t(1) << 16 : std::max<std::size_t>(count, 1);
  for (std::size_t c0 = 0; c0 < count; c0 += chunk) {
    const std::size_t c1 = std::min(count, c0 + chunk);
    parallel_for(c1 - c0, threads, [&](std::size_t b, std::size_t e) {
      TouchBox mine;
      for (std::size_t i = c0 + b; i < c0 + e; ++i) cast(i, mine);
      std::lock_guard<std::mutex> lock(box_mutex);
      box.merge(mine);
    });
    if (progress_ && !progress_(c1, count)) {
      for_box_rows(box, frame_.dims, threads, [&](std::size_t row, std::size_t x0, std::size_t x1) {
        std::fill(marks + row + x0, marks + row + x1, std::uint8_t(0));
      });
      throw Error(Status::cancelled, "ray casting cancelled by the progress callback");
    }
  }
  const float lh = l_hit_, lm = l_miss_, lo = l_min_, hi = l_max_;
  float* lodds = log_odds_.data();
  for_box_rows(box, frame_.dims, threads, [&](std::size_t row, std::size_t x0, std::size_t x1) {
    std::uint8_t* m = marks + row;
    float* l = lodds + row;
    for (std::size_t x = x0; x < x1; ++x) {
      if (x % 8 == 0 && x + 8 <= x1) {  // skip 8 unmarked voxels at a time
        std::uint64_t w;
        std::memcpy(&w, m + x, 8);
        if (w == 0) {
          x += 7;
          continue;
        }
      }
      const std::uint8_t v = m[x];
      if (!v) continue;
      l[x] = std::clamp(l[x] + ((v & 2) ? lh : lm), lo, hi);
      m[x] = 0;
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
