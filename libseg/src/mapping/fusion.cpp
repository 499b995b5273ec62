// Scan fusion into an occupancy grid (occseg/fusion.hpp): rays set up here, walked by the kernels.
#include "occseg/fusion.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

#include "occseg/error.hpp"
#include "kernels/kernels.hpp"
#include "occseg/parallel.hpp"
#include "util/huge_pages.hpp"

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
  resize_huge(log_odds_, frame.dims.count());  // zero-filled, on 2 MB pages where possible
  resize_huge(marks_, frame.dims.count());
}

namespace {

// The walks' state and the kernels that walk them (kernels/fusion.hpp).
using kernels::TouchBox;
using kernels::Walk;

// floor(p) clamped to the voxels [0, n - 1] of an axis, clamped while still a double: a ray from
// a sensor 10^36 voxels away rounds p to 10^22 or so, and converting such a double (or a NaN) to
// long is undefined. Equal to clamp(long(floor(p))) wherever that is defined.
long voxel_on_axis(double p, double n) {
  const double f = std::floor(p);
  if (!(f > 0)) return 0;  // NaN too
  return f < n - 1 ? static_cast<long>(f) : static_cast<long>(n) - 1;
}

// Sets up the traversal of the segment a -> b (grid units: (world - origin) / voxel_size),
// clipped to the grid box; false when the segment misses the box. The floating-point arithmetic
// (clipping, tmax, tdelta, and in the kernels' steps the axis choice and tmax updates) is exactly
// that of the plain walk the tests compare with (reference_trace in tests/cpp/test_fusion.cpp),
// so the same voxels are visited.
bool start_walk(const double* a, const double* b, bool hit, const Dims& dims, Walk& w, TouchBox& box) {
  const double n[3] = {double(dims.nx), double(dims.ny), double(dims.nz)};
  double d[3];
  for (int k = 0; k < 3; ++k) d[k] = b[k] - a[k];
  // Clip the parameter range [t0, t1] of a + t d to the box [0, n] (slab method).
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (a[k] < 0 || a[k] >= n[k]) return false;
      continue;
    }
    double ta = (0 - a[k]) / d[k], tb = (n[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return false;
  const bool end_inside = hit && t1 >= 1.0;
  const std::uint64_t nx = dims.nx, nxy = nx * dims.ny;
  long c[3], last[3];
  double tmax[3], tdelta[3];
  for (int k = 0; k < 3; ++k) {
    const double p = a[k] + t0 * d[k];
    c[k] = voxel_on_axis(p, n[k]);
    const double q = a[k] + t1 * d[k];
    last[k] = voxel_on_axis(q, n[k]);
    if (d[k] > 0) {
      w.step[k] = 1;
      tmax[k] = (c[k] + 1 - a[k]) / d[k];
      tdelta[k] = 1 / d[k];
    } else if (d[k] < 0) {
      w.step[k] = -1;
      tmax[k] = (c[k] - a[k]) / d[k];
      tdelta[k] = -1 / d[k];
    } else {
      w.step[k] = 0;
      tmax[k] = tdelta[k] = std::numeric_limits<double>::infinity();
    }
    w.c0[k] = c[k];
    // Steps left along the axis before the walk would leave the grid (the first implementation
    // stopped there); an axis with d = 0 is never taken (its tmax is +inf).
    w.room[k] = w.step[k] > 0 ? static_cast<long>(n[k]) - 1 - c[k]
                              : (w.step[k] < 0 ? c[k] : std::numeric_limits<long>::max());
  }
  box.add(c);
  // Bounded walk: at most the number of voxel faces crossed plus one.
  w.budget = std::labs(last[0] - c[0]) + std::labs(last[1] - c[1]) + std::labs(last[2] - c[2]) + 1;
  w.i = static_cast<std::uint64_t>(c[0]) + nx * static_cast<std::uint64_t>(c[1]) + nxy * static_cast<std::uint64_t>(c[2]);
  w.end = static_cast<std::uint64_t>(last[0]) + nx * static_cast<std::uint64_t>(last[1]) +
          nxy * static_cast<std::uint64_t>(last[2]);
  // Unsigned wrap-around makes a step of -1 subtract the stride.
  w.sx = static_cast<std::uint64_t>(w.step[0]);
  w.sy = static_cast<std::uint64_t>(w.step[1]) * nx;
  w.sz = static_cast<std::uint64_t>(w.step[2]) * nxy;
  w.rx = w.room[0];
  w.ry = w.room[1];
  w.rz = w.room[2];
  w.tx[0] = tmax[0], w.ty[0] = tmax[1], w.tz[0] = tmax[2];
  w.dx[0] = tdelta[0], w.dy[0] = tdelta[1], w.dz[0] = tdelta[2];
  w.tx[1] = w.ty[1] = w.tz[1] = w.dx[1] = w.dy[1] = w.dz[1] = 0;
  w.hit = end_inside;
  w.at_end = false;
  return true;
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
  auto start = [&](std::size_t i, Walk& w, TouchBox& box) {
    const float* p = xyz + i * stride;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return false;
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
    return start_walk(a, b, hit, frame_.dims, w, box);
  };
  // Walks rays [r, e) with the kernels of this call (several at a time, depending on the level).
  const kernels::FusionKernels& kernel = kernels::active().fusion;
  auto walk_rays = [&](std::size_t r, std::size_t e, TouchBox& box, std::vector<std::uint64_t>& hits) {
    auto next = [&](Walk& w) {
      while (r < e)
        if (start(r++, w, box)) return true;
      return false;
    };
    kernel.walk_rays(kernels::NextRay(next), marks, frame_.dims, box, hits);
  };
  TouchBox box;
  std::vector<std::uint64_t> hits;  // end voxels holding a return, written after the walks
  std::mutex box_mutex;
  // With a progress callback rays go in chunks, so long scans report; marks only ever grow, so
  // the chunking changes nothing in the result.
  const std::size_t chunk = progress_ ? std::size_t(1) << 16 : std::max<std::size_t>(count, 1);
  for (std::size_t c0 = 0; c0 < count; c0 += chunk) {
    const std::size_t c1 = std::min(count, c0 + chunk);
    // Threads take blocks of rays from a shared counter: ray lengths vary across a cloud (floor
    // near, wall far), so fixed halves left one thread idle. Marks only ever grow, so which
    // thread walks which ray changes nothing.
    constexpr std::size_t kBlock = 2048;
    const std::size_t blocks = (c1 - c0 + kBlock - 1) / kBlock;
    std::atomic<std::size_t> next{0};
    parallel_for(std::min<std::size_t>(blocks, resolve_threads(threads)), threads, [&](std::size_t, std::size_t) {
      TouchBox mine;
      std::vector<std::uint64_t> my_hits;
      for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < blocks;)
        walk_rays(c0 + k * kBlock, std::min(c1, c0 + (k + 1) * kBlock), mine, my_hits);
      std::lock_guard<std::mutex> lock(box_mutex);
      box.merge(mine);
      hits.insert(hits.end(), my_hits.begin(), my_hits.end());
    });
    // Hits go in once every walk of the chunk is over: a concurrent "crossed" mark could have
    // overwritten them (it stores without a locked read-modify-write).
    for (std::uint64_t h : hits) marks[h] = 2;
    hits.clear();
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

bool endpoint_voxel(const GridFrame& frame, const Vec3& sensor, const float end[3], std::uint64_t& index) {
  if (!std::isfinite(end[0]) || !std::isfinite(end[1]) || !std::isfinite(end[2])) return false;
  // As insert_scan computes a (the sensor) and b (the endpoint) in grid units.
  const double vs = frame.voxel_size;
  const double a[3] = {(sensor[0] - frame.origin[0]) / vs, (sensor[1] - frame.origin[1]) / vs,
                       (sensor[2] - frame.origin[2]) / vs};
  const Vec3 e{end[0], end[1], end[2]};
  double b[3];
  for (int k = 0; k < 3; ++k) b[k] = (e[k] - frame.origin[k]) / vs;
  Walk w;
  TouchBox box;
  if (!start_walk(a, b, true, frame.dims, w, box) || !w.hit) return false;
  index = w.end;
  return true;
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
    // Far from the world origin b - a can round to 0 (floor(x) + 1 == floor(x)): out of range.
    if (!(b - a >= 1))
      throw Error(Status::bad_value, "points this far from the world origin are out of range for voxels of " +
                                         std::to_string(voxel_size) + " m");
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
