// occseg_fusion_* and occseg_result_point_labels: clouds held as arrays fused into a map through
// the readers' own scan layer (ScanBounds, ScanFusion of adapters/scan), so an array gives the
// map a .pcd file of the same points gives; and each input point's segment.
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "internal.hpp"
#include "occseg/scan_options.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::invalid;
using occseg::capi::number;
using occseg::capi::require;

namespace {

// One scan as the caller passed it, copied packed (x, y, z of T per point): the caller's memory
// is read once, here, at any alignment and stride.
template <class T>
std::vector<T> packed_copy(const char* base, std::size_t count, ptrdiff_t stride) {
  std::vector<T> xyz(3 * count);
  for (std::size_t i = 0; i < count; ++i)
    std::memcpy(&xyz[3 * i], base + static_cast<ptrdiff_t>(i) * stride, 3 * sizeof(T));
  return xyz;
}

// The points of one call, checked: a packed copy in float or double.
struct Points {
  bool is_double = false;
  std::vector<float> f;
  std::vector<double> d;
  std::size_t count = 0;
  const float* floats() const { return f.data(); }
  const double* doubles() const { return d.data(); }
};

Points read_points(const void* points, const occseg_dtype& dtype, std::size_t count, ptrdiff_t stride) {
  require(points, "points");
  const int dt = occseg::capi::enum_value(dtype);
  if (dt != OCCSEG_F32 && dt != OCCSEG_F64)
    invalid("dtype " + std::to_string(dt) + " is not OCCSEG_F32 or OCCSEG_F64 (point coordinates are floats)");
  if (count == 0) invalid("count is 0: a scan needs at least one point");
  const std::size_t item = dt == OCCSEG_F32 ? 4 : 8;
  if (stride == 0) stride = static_cast<ptrdiff_t>(3 * item);
  if (stride == std::numeric_limits<ptrdiff_t>::min()) invalid("stride " + std::to_string(stride) + " overflows");
  const std::size_t step = static_cast<std::size_t>(stride < 0 ? -stride : stride);
  if (step < 3 * item)
    invalid("stride " + std::to_string(stride) + " is smaller than a point's 3 coordinates (" +
            std::to_string(3 * item) + " bytes): points would overlap");
  std::size_t span;
  if (__builtin_mul_overflow(step, count - 1, &span) ||
      span > static_cast<std::size_t>(std::numeric_limits<ptrdiff_t>::max()) - 3 * item)
    invalid("count " + std::to_string(count) + " points of stride " + std::to_string(stride) +
            " span more bytes than an address can hold");
  Points p;
  p.count = count;
  p.is_double = dt == OCCSEG_F64;
  const char* base = static_cast<const char*>(points);
  if (p.is_double)
    p.d = packed_copy<double>(base, count, stride);
  else
    p.f = packed_copy<float>(base, count, stride);
  return p;
}

// The pose of a scan (make_pose: normalised quaternion, Error(bad_value) for a bad one).
Eigen::Isometry3d read_pose(const double origin[3], const double orientation[4]) {
  const occseg::Vec3 o = origin ? occseg::Vec3{origin[0], origin[1], origin[2]} : occseg::Vec3{0, 0, 0};
  const std::array<double, 4> q = orientation ? std::array<double, 4>{orientation[0], orientation[1], orientation[2],
                                                                      orientation[3]}
                                              : std::array<double, 4>{1, 0, 0, 0};
  for (double v : o)
    if (!std::isfinite(v)) throw Error(Status::bad_value, "sensor origin (" + number(o[0]) + ", " + number(o[1]) + ", " +
                                                              number(o[2]) + ") is not finite");
  for (double v : q)
    if (!std::isfinite(v))
      throw Error(Status::bad_value, "sensor orientation (w, x, y, z) = (" + number(q[0]) + ", " + number(q[1]) + ", " +
                                         number(q[2]) + ", " + number(q[3]) + ") is not finite");
  return occseg::make_pose(o, q);
}

std::size_t finite_points(const Points& p) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.count; ++i) {
    const bool ok = p.is_double ? std::isfinite(p.d[3 * i]) && std::isfinite(p.d[3 * i + 1]) && std::isfinite(p.d[3 * i + 2])
                                : std::isfinite(p.f[3 * i]) && std::isfinite(p.f[3 * i + 1]) && std::isfinite(p.f[3 * i + 2]);
    n += ok;
  }
  return n;
}

}  // namespace

struct occseg_fusion {
  struct Scan {
    Eigen::Isometry3d pose;
    Points points;
  };
  occseg_fusion_options options{};
  occseg::SensorModel model;
  std::optional<occseg::ScanFusion> fixed;  // use_box: the scans go in as they come
  std::vector<Scan> scans;                  // otherwise: buffered until occseg_fusion_map
  occseg::ScanBounds bounds;                // of the buffered scans
  std::uint64_t scan_count = 0, finite = 0;

  void add(const Eigen::Isometry3d& pose, const Points& p, int threads) {
    if (p.is_double)
      fixed->insert(pose, p.doubles(), p.count, 3, threads);
    else
      fixed->insert(pose, p.floats(), p.count, 3, threads);
  }
};

extern "C" {

void occseg_fusion_options_init(occseg_fusion_options* opts) {
  if (!opts) return;
  const occseg_fusion_options defaults = OCCSEG_FUSION_OPTIONS_INIT;
  *opts = defaults;
}

int occseg_fusion_new(occseg_fusion** out, const occseg_fusion_options* opts) {
  return guard("occseg_fusion_new", [&] {
    require(out, "out");
    *out = nullptr;
    occseg_fusion_options o;
    occseg_fusion_options_init(&o);
    if (opts) {
      if (opts->struct_size != sizeof(occseg_fusion_options))
        invalid("opts->struct_size " + std::to_string(opts->struct_size) + " is not sizeof(occseg_fusion_options) = " +
                std::to_string(sizeof(occseg_fusion_options)) + " (use OCCSEG_FUSION_OPTIONS_INIT)");
      o = *opts;
    }
    if (!(o.voxel_size > 0) || !std::isfinite(o.voxel_size))
      throw Error(Status::bad_value, "voxel_size " + number(o.voxel_size) + " is not a positive finite number");
    if (!(o.margin >= 0) || !std::isfinite(o.margin)) invalid("margin " + number(o.margin) + " is not a non-negative number");
    if (o.threads < 0 || o.threads > 1024) invalid("threads " + std::to_string(o.threads) + " is outside [0, 1024]");
    if (std::isnan(o.max_range)) invalid("max_range is NaN (a negative value means unlimited)");
    auto f = std::make_unique<occseg_fusion>();
    f->options = o;
    f->model.max_range = o.max_range;
    f->model.validate();
    if (o.use_box) {
      const occseg::Box box{{o.box_min[0], o.box_min[1], o.box_min[2]}, {o.box_max[0], o.box_max[1], o.box_max[2]}};
      f->fixed.emplace(occseg::frame_for_box(box, o.voxel_size), f->model);
    }
    *out = f.release();
  });
}

void occseg_fusion_free(occseg_fusion* fusion) { delete fusion; }

int occseg_fusion_add_points(occseg_fusion* fusion, const void* points, occseg_dtype dtype, size_t count,
                             ptrdiff_t stride, const double origin[3], const double orientation_wxyz[4]) {
  return guard("occseg_fusion_add_points", [&] {
    require(fusion, "fusion");
    const Eigen::Isometry3d pose = read_pose(origin, orientation_wxyz);
    Points p = read_points(points, dtype, count, stride);
    const std::size_t finite = finite_points(p);
    const occseg_fusion_options& o = fusion->options;
    if (fusion->fixed) {
      fusion->add(pose, p, o.threads);  // throws before touching the grid (sensor out of range)
    } else {
      // The box of all scans so far must stay a valid grid: checked now, on a copy, so a scan
      // that would break it is refused with the fusion unchanged.
      occseg::ScanBounds b = fusion->bounds;
      if (p.is_double)
        b.add(pose, p.doubles(), p.count, 3, o.max_range);
      else
        b.add(pose, p.floats(), p.count, 3, o.max_range);
      (void)b.frame(o.voxel_size, o.margin);
      fusion->scans.push_back({pose, std::move(p)});
      fusion->bounds = b;
    }
    ++fusion->scan_count;
    fusion->finite += finite;
  });
}

int occseg_fusion_map(occseg_map** out, const occseg_fusion* fusion) {
  return guard("occseg_fusion_map", [&] {
    require(out, "out");
    *out = nullptr;
    require(fusion, "fusion");
    if (!fusion->finite)
      throw Error(Status::bad_value, "no finite point in the " + std::to_string(fusion->scan_count) +
                                         " scan(s) added: nothing to fuse");
    auto m = std::make_unique<occseg_map>();
    if (fusion->fixed) {
      m->grid = fusion->fixed->grid();
    } else {
      // As integrate_clouds fuses the clouds of a .pcd: the box fitted to all, then each scan.
      const occseg_fusion_options& o = fusion->options;
      occseg::ScanFusion f(fusion->bounds.frame(o.voxel_size, o.margin), fusion->model);
      for (const occseg_fusion::Scan& s : fusion->scans) {
        if (s.points.is_double)
          f.insert(s.pose, s.points.doubles(), s.points.count, 3, o.threads);
        else
          f.insert(s.pose, s.points.floats(), s.points.count, 3, o.threads);
      }
      m->grid = f.grid();
    }
    *out = m.release();
  });
}

int occseg_fusion_counts(const occseg_fusion* fusion, uint64_t* scans, uint64_t* points) {
  return guard("occseg_fusion_counts", [&] {
    require(fusion, "fusion");
    if (scans) *scans = fusion->scan_count;
    if (points) *points = fusion->finite;
  });
}

int occseg_result_point_labels(const occseg_result* result, const occseg_map* map, const void* points,
                               occseg_dtype dtype, size_t count, ptrdiff_t stride, const double origin[3],
                               const double orientation_wxyz[4], uint32_t* out, size_t out_count) {
  return guard("occseg_result_point_labels", [&] {
    require(result, "result");
    require(out, "out");
    const occseg::Result& r = result->result;
    occseg::GridFrame frame;
    frame.dims = r.dims;
    frame.voxel_size = result->voxel_size;
    frame.origin = result->origin;
    if (map) {
      const occseg::Dims& d = map->grid.dims;
      if (!(d == r.dims))
        invalid("map (" + std::to_string(d.nx) + " x " + std::to_string(d.ny) + " x " + std::to_string(d.nz) +
                ") is not the map the result (" + std::to_string(r.dims.nx) + " x " + std::to_string(r.dims.ny) +
                " x " + std::to_string(r.dims.nz) + ") was computed on");
      frame.voxel_size = map->grid.voxel_size;
      frame.origin = map->grid.origin;
    }
    const Eigen::Isometry3d pose = read_pose(origin, orientation_wxyz);
    const Points p = read_points(points, dtype, count, stride);
    if (out_count < count)
      throw Error(Status::out_of_range, "out_count " + std::to_string(out_count) + " is smaller than the " +
                                            std::to_string(count) + " points");
    const occseg::LabelArray& labels = r.labels;
    const auto label = [&labels](std::uint64_t v) { return labels[static_cast<std::size_t>(v)]; };
    if (p.is_double)
      occseg::scan_point_voxels(frame, pose, p.doubles(), p.count, 3, out, label);
    else
      occseg::scan_point_voxels(frame, pose, p.floats(), p.count, 3, out, label);
  });
}

}  // extern "C"
