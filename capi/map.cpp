// occseg_map_*: maps from caller buffers (any dtype, any non-overlapping strides) and .npy files.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>

#include "internal.hpp"
#include "occseg/geometry.hpp"
#include "occseg/map_yaml.hpp"
#include "occseg/fill_values.hpp"
#include "occseg/npy.hpp"
#include "occseg/parallel.hpp"

using occseg::Dims;
using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::invalid;
using occseg::capi::number;
using occseg::capi::require;

namespace {

std::size_t item_size(int dtype) {
  switch (dtype) {
    case OCCSEG_F32: return 4;
    case OCCSEG_F64: return 8;
    case OCCSEG_U8: return 1;
    case OCCSEG_U16: return 2;
    case OCCSEG_I8_OCCUPANCY: return 1;
    default: invalid("dtype " + std::to_string(dtype) + " is not an occseg_dtype (OCCSEG_F32 .. OCCSEG_I8_OCCUPANCY)");
  }
}

void check_voxel_size(double v) {
  if (!(v > 0) || !std::isfinite(v))
    throw Error(Status::bad_value, "voxel_size " + number(v, 6) + " is not a positive finite number");
}

// Rejects strides under which two voxels would share bytes, or whose extent overflows
// ptrdiff_t. Sufficient test: ordered by |stride|, each axis must step over the whole extent
// of the finer ones (true of every C, Fortran, sliced, transposed or flipped array).
void check_strides(const Dims& d, const ptrdiff_t s[3], std::size_t item) {
  const std::size_t n[3] = {d.nx, d.ny, d.nz};
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) {
    return s[a] == std::numeric_limits<ptrdiff_t>::min() ? false
           : s[b] == std::numeric_limits<ptrdiff_t>::min() ? true
                                                            : std::llabs(s[a]) < std::llabs(s[b]);
  });
  std::size_t extent = item;  // bytes covered by the finer axes, from the lowest to past the highest
  const std::size_t limit = static_cast<std::size_t>(std::numeric_limits<ptrdiff_t>::max());
  for (int k : order) {
    if (n[k] == 1) continue;  // the stride of a single-voxel axis is never used
    const std::string which = "strides[" + std::to_string(k) + "] = " + std::to_string(s[k]);
    if (s[k] == std::numeric_limits<ptrdiff_t>::min()) invalid(which + " overflows");
    const std::size_t step = static_cast<std::size_t>(std::llabs(s[k]));
    if (step < extent)
      invalid(which + " makes voxels overlap (each step must skip the " + std::to_string(extent) +
              " bytes spanned by the finer axes)");
    std::size_t span;
    if (__builtin_mul_overflow(step, n[k] - 1, &span) || __builtin_add_overflow(span, extent, &extent) ||
        extent > limit)
      invalid(which + " makes the map span more bytes than an address can hold");
  }
}

template <class T>
T load(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);  // any alignment
  return v;
}

// An item stored in the opposite byte order when `swapped` (OCCSEG_IMPORT_BYTE_SWAPPED).
template <class T>
T load(const char* p, bool swapped) {
  if (!swapped) return load<T>(p);
  char b[sizeof(T)];
  for (std::size_t k = 0; k < sizeof(T); ++k) b[k] = p[sizeof(T) - 1 - k];
  return load<T>(b);
}

constexpr uint32_t kSwapped = OCCSEG_IMPORT_BYTE_SWAPPED;

[[noreturn]] void bad_value(std::size_t x, std::size_t y, std::size_t z, double v) {
  const char* what = std::isnan(v) ? "is NaN" : (std::isinf(v) ? "is infinite" : "is outside [0, 1]");
  // The one flag that accepts this value (the Python bindings put their keyword in its place).
  const char* fix = std::isnan(v) ? " (pass OCCSEG_IMPORT_NAN_UNKNOWN to read it as unknown)"
                                  : " (pass OCCSEG_IMPORT_CLAMP to clamp it to [0, 1])";
  throw Error(Status::bad_value, "data: probability at voxel (" + std::to_string(x) + ", " + std::to_string(y) +
                                     ", " + std::to_string(z) + ") = " + number(v, 9) + " " + what + fix);
}

// One F32/F64 value as a probability, per the import flags.
float probability(double v, uint32_t flags, std::size_t x, std::size_t y, std::size_t z) {
  if (v >= 0.0 && v <= 1.0) return static_cast<float>(v);
  if (std::isnan(v)) {
    if (flags & OCCSEG_IMPORT_NAN_UNKNOWN) return 0.5f;
  } else if (flags & OCCSEG_IMPORT_CLAMP) {
    return v < 0.0 ? 0.0f : 1.0f;
  }
  bad_value(x, y, z, v);
}

// One nav_msgs/OccupancyGrid cell, converted as the map_server reader converts its cells.
float occupancy(int8_t v, std::size_t x, std::size_t y, std::size_t z) {
  float p;
  if (occseg::occupancy_cell_probability(v, p)) return p;
  throw Error(Status::bad_value, "data: OccupancyGrid cell (" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                                     std::to_string(z) + ") = " + std::to_string(v) +
                                     " is neither -1 (unknown) nor an occupancy in 0..100");
}

// Rows [r0, r1) (row r = y + ny * z) of the buffer as probabilities into out[x + nx * r].
template <class Value>
void convert_rows(float* out, const Dims& d, const char* base, const ptrdiff_t s[3], std::size_t r0, std::size_t r1,
                  Value value) {
  for (std::size_t r = r0; r < r1; ++r) {
    const std::size_t z = r / d.ny, y = r % d.ny;
    const char* row = base + static_cast<ptrdiff_t>(z) * s[2] + static_cast<ptrdiff_t>(y) * s[1];
    float* const o = out + r * d.nx;
    for (std::size_t x = 0; x < d.nx; ++x) o[x] = value(row + static_cast<ptrdiff_t>(x) * s[0], x, y, z);
  }
}

// The buffer's values as probabilities into out[x + nx * (y + ny * z)], checked as documented
// for occseg_map_from_buffer (the first bad voxel in x-fastest order is named). Large maps are
// converted by several threads; when one of them meets a bad value, the rows are converted again
// in order on this thread, which names the first one.
void convert(float* out, const Dims& d, const char* base, int dtype, const ptrdiff_t s[3], uint32_t flags,
             int threads = 0) {
  auto run = [&](auto value) {
    const std::size_t rows = d.ny * d.nz;
    const int t = d.count() >= (std::size_t(1) << 21) ? std::min(occseg::resolve_threads(threads), 8) : 1;
    std::atomic<bool> bad{false};
    if (t > 1) {
      occseg::parallel_for(rows, t, [&](std::size_t r0, std::size_t r1) {
        try {
          convert_rows(out, d, base, s, r0, r1, value);
        } catch (const Error&) {
          bad.store(true);
        }
      });
    }
    if (t <= 1 || bad.load()) convert_rows(out, d, base, s, 0, rows, value);
  };
  const bool sw = flags & kSwapped;
  switch (dtype) {
    case OCCSEG_F32:
      run([flags, sw](const char* e, std::size_t x, std::size_t y, std::size_t z) { return probability(load<float>(e, sw), flags, x, y, z); });
      break;
    case OCCSEG_F64:
      run([flags, sw](const char* e, std::size_t x, std::size_t y, std::size_t z) { return probability(load<double>(e, sw), flags, x, y, z); });
      break;
    // Same conversion as the .npy reader, so both paths give identical maps.
    case OCCSEG_U8:
      run([](const char* e, std::size_t, std::size_t, std::size_t) { return static_cast<float>(load<uint8_t>(e) / 255.0); });
      break;
    case OCCSEG_I8_OCCUPANCY:
      run([](const char* e, std::size_t x, std::size_t y, std::size_t z) { return occupancy(load<int8_t>(e), x, y, z); });
      break;
    default:
      run([sw](const char* e, std::size_t, std::size_t, std::size_t) { return static_cast<float>(load<uint16_t>(e, sw) / 65535.0); });
      break;
  }
}

// Voxels [i, i + n) (rows crossed) of the buffer as probabilities into out[0, n), by `value` as
// convert_rows() converts them (so it throws as convert() does for the first bad one of the run).
template <class Value>
void convert_run(float* out, const Dims& d, const char* base, const ptrdiff_t s[3], std::size_t i, std::size_t n,
                 Value value) {
  while (n > 0) {
    const std::size_t r = i / d.nx, x0 = i % d.nx, m = std::min(n, d.nx - x0);
    const std::size_t z = r / d.ny, y = r % d.ny;
    const char* row = base + static_cast<ptrdiff_t>(z) * s[2] + static_cast<ptrdiff_t>(y) * s[1];
    for (std::size_t x = x0; x < x0 + m; ++x) *out++ = value(row + static_cast<ptrdiff_t>(x) * s[0], x, y, z);
    i += m;
    n -= m;
  }
}

// A viewed buffer read through the stages' MapSource: runs of voxels converted as convert() would
// convert them (the same floats, the same first bad voxel and text), into the stages' scratch.
// Runs along a dense x of the common dtypes take loops of their own; the rest, and every run with
// an import flag, go through convert()'s own per-voxel conversion.
class BufferSource final : public occseg::MapSource {
 public:
  BufferSource(const Dims& d, const occseg_map::View& v) : d_(d), v_(v) {}

  bool read(std::size_t i, std::size_t n, float* out) const override {
    const ptrdiff_t* s = v_.strides;
    const std::size_t item = dtype_size();
    if (s[0] == static_cast<ptrdiff_t>(item) || d_.nx == 1) {
      bool ok = true;
      while (n > 0 && ok) {
        const std::size_t r = i / d_.nx, x0 = i % d_.nx, m = std::min(n, d_.nx - x0);
        const char* e = v_.data + static_cast<ptrdiff_t>(r / d_.ny) * s[2] + static_cast<ptrdiff_t>(r % d_.ny) * s[1] +
                        static_cast<ptrdiff_t>(x0 * item);
        if (!dense_run(e, m, out, ok)) break;  // no loop of its own: the general one below
        i += m, n -= m, out += m;
      }
      if (n == 0 || !ok) return ok;
    }
    try {
      convert_run_any(out, i, n);
      return true;
    } catch (const Error&) {
      return false;
    }
  }

  [[noreturn]] void fail() const override {
    check();
    throw Error(Status::internal, "a borrowed map's value was refused, then converted");  // (never reached)
  }

  // Throws what convert() throws for the buffer (the first bad voxel in x-fastest order), if it does.
  void check() const {
    std::vector<float> row(d_.nx);
    for (std::size_t r = 0; r < d_.ny * d_.nz; ++r) convert_run_any(row.data(), r * d_.nx, d_.nx);
  }

 private:
  std::size_t dtype_size() const { return item_size(v_.dtype); }

  // A run of m voxels of one row, contiguous at e, by a loop of its own for the dtype: false when
  // it has none (an import flag, or the occupancy dtype); else ok = no value refused.
  bool dense_run(const char* e, std::size_t m, float* out, bool& ok) const {
    const bool sw = v_.flags & kSwapped;
    switch (v_.dtype) {
      case OCCSEG_F32:
        if (v_.flags & ~kSwapped) return false;
        ok = sw ? float_run<float, true>(e, m, out) : float_run<float, false>(e, m, out);
        return true;
      case OCCSEG_F64:
        if (v_.flags & ~kSwapped) return false;
        ok = sw ? float_run<double, true>(e, m, out) : float_run<double, false>(e, m, out);
        return true;
      case OCCSEG_U8:  // (convert()'s expression: the compiler vectorises it)
        for (std::size_t x = 0; x < m; ++x) out[x] = static_cast<float>(static_cast<unsigned char>(e[x]) / 255.0);
        return true;
      case OCCSEG_U16:
        if (sw) {
          for (std::size_t x = 0; x < m; ++x) out[x] = static_cast<float>(load<uint16_t>(e + 2 * x, true) / 65535.0);
        } else {
          for (std::size_t x = 0; x < m; ++x) out[x] = static_cast<float>(load<uint16_t>(e + 2 * x) / 65535.0);
        }
        return true;
      default:
        return false;
    }
  }

  // m contiguous F32/F64 items as probabilities without an import flag: float(v), and true when
  // every v lies in [0, 1] (what probability() accepts without a flag).
  template <class T, bool Swapped>
  static bool float_run(const char* e, std::size_t m, float* out) {
    if (!Swapped) return std::is_same<T, float>::value ? f32_run(e, m, out) : f64_run(e, m, out);
    bool good = true;
    for (std::size_t x = 0; x < m; ++x) {
      const T v = load<T>(e + sizeof(T) * x, true);
      good = good && v >= T(0) && v <= T(1);
      out[x] = static_cast<float>(v);
    }
    return good;
  }

  // The native-order loops, written as masks so that the compiler vectorises them (the double
  // test needs 64-bit integer compares: AVX2 where the processor has it).
  static bool f32_run(const char* e, std::size_t m, float* out) {
    int32_t bad = 0;
    for (std::size_t x = 0; x < m; ++x) {
      const float v = load<float>(e + 4 * x);
      bad |= (v >= 0.0f ? 0 : -1) | (v <= 1.0f ? 0 : -1);
      out[x] = v;
    }
    return bad == 0;
  }
#if defined(__x86_64__) && defined(__GNUC__)
  __attribute__((target_clones("avx2", "default")))
#endif
  static bool f64_run(const char* e, std::size_t m, float* out) {
    for (std::size_t x = 0; x < m; ++x) out[x] = static_cast<float>(load<double>(e + 8 * x));
    int64_t bad = 0;
    for (std::size_t x = 0; x < m; ++x) {
      const double v = load<double>(e + 8 * x);
      bad |= (v >= 0.0 ? 0 : -1) | (v <= 1.0 ? 0 : -1);
    }
    return bad == 0;
  }

  // convert()'s per-voxel conversion of voxels [i, i + n): throws at the first bad one.
  void convert_run_any(float* out, std::size_t i, std::size_t n) const {
    const ptrdiff_t* s = v_.strides;
    const uint32_t flags = v_.flags;
    const bool sw = flags & kSwapped;
    switch (v_.dtype) {
      case OCCSEG_F32:
        convert_run(out, d_, v_.data, s, i, n, [flags, sw](const char* e, std::size_t x, std::size_t y, std::size_t z) {
          return probability(load<float>(e, sw), flags, x, y, z);
        });
        break;
      case OCCSEG_F64:
        convert_run(out, d_, v_.data, s, i, n, [flags, sw](const char* e, std::size_t x, std::size_t y, std::size_t z) {
          return probability(load<double>(e, sw), flags, x, y, z);
        });
        break;
      case OCCSEG_U8:
        convert_run(out, d_, v_.data, s, i, n, [](const char* e, std::size_t, std::size_t, std::size_t) {
          return static_cast<float>(load<uint8_t>(e) / 255.0);
        });
        break;
      case OCCSEG_I8_OCCUPANCY:
        convert_run(out, d_, v_.data, s, i, n, [](const char* e, std::size_t x, std::size_t y, std::size_t z) {
          return occupancy(load<int8_t>(e), x, y, z);
        });
        break;
      default:
        convert_run(out, d_, v_.data, s, i, n, [sw](const char* e, std::size_t, std::size_t, std::size_t) {
          return static_cast<float>(load<uint16_t>(e, sw) / 65535.0);
        });
        break;
    }
  }

  Dims d_;
  occseg_map::View v_;
};

// The checks of occseg_map_from_buffer_flags and occseg_map_view_buffer, in their order: a map
// with dims and voxel size set and `view` describing the buffer (strides filled in).
std::unique_ptr<occseg_map> checked_map(occseg_map** out, const void* data, const occseg_dtype& dtype, const size_t dims[3],
                                        const ptrdiff_t strides[3], double voxel_size, uint32_t flags) {
  require(out, "out");
  *out = nullptr;
  require(data, "data");
  require(dims, "dims");
  const int dt = occseg::capi::enum_value(dtype);
  const std::size_t item = item_size(dt);
  if (flags & ~uint32_t(OCCSEG_IMPORT_CLAMP | OCCSEG_IMPORT_NAN_UNKNOWN | OCCSEG_IMPORT_BYTE_SWAPPED))
    invalid("flags " + std::to_string(flags) + " has bits that are no occseg_import_flags");
  const Dims d{dims[0], dims[1], dims[2]};
  occseg::check_dims(d);
  check_voxel_size(voxel_size);
  occseg::check_geometry(d, voxel_size, {0, 0, 0});  // the far corner must not overflow
  auto m = std::make_unique<occseg_map>();
  ptrdiff_t* s = m->view.strides;
  if (strides) {
    std::copy(strides, strides + 3, s);
    check_strides(d, s, item);
  } else {  // dense: fits, since check_dims bounds the voxel count by 2^40
    s[0] = static_cast<ptrdiff_t>(item);
    s[1] = s[0] * static_cast<ptrdiff_t>(d.nx);
    s[2] = s[1] * static_cast<ptrdiff_t>(d.ny);
  }
  m->grid.dims = d;
  m->grid.voxel_size = voxel_size;
  m->view.data = static_cast<const char*>(data);
  m->view.dtype = dt;
  m->view.flags = flags;
  return m;
}

// True when the viewed buffer is laid out as a Grid's values: native float32, x fastest, dense (the
// stride of a one-voxel axis is never used, so any value there is dense).
bool dense_f32(const occseg_map& m) {
  const Dims& d = m.grid.dims;
  const ptrdiff_t* s = m.view.strides;
  return m.view.dtype == OCCSEG_F32 && !(m.view.flags & kSwapped) && (d.nx == 1 || s[0] == 4) &&
         (d.ny == 1 || s[1] == static_cast<ptrdiff_t>(4 * d.nx)) &&
         (d.nz == 1 || s[2] == static_cast<ptrdiff_t>(4 * d.nx * d.ny));
}

void dims_out(const Dims& d, size_t dims[3]) {
  dims[0] = d.nx;
  dims[1] = d.ny;
  dims[2] = d.nz;
}

}  // namespace

namespace occseg::capi {

void with_values(const occseg_map* map, const std::function<void(const Grid&)>& fn, int) {
  if (!map->is_view) return fn(map->grid);
  const occseg_map::View& v = map->view;
  const Grid& g = map->grid;
  const BufferSource source(g.dims, v);
  // A float32 buffer that needs no import flag is read where it lies.
  if (g.borrowed && (v.flags == 0 || occseg::probabilities_in_range(g.borrowed, g.dims.count()))) {
    try {
      return fn(g);
    } catch (const Error& e) {
      if (e.status() != Status::bad_value) throw;
      // The pipeline found a value outside [0, 1] (it names it its own way): name the first one
      // as occseg_map_from_buffer does.
      source.check();
      throw;
    }
  }
  // Any other buffer through a converter: the stages convert the runs they read (MapSource), so
  // no float copy of the map is made; the first bad value fails as in the copy path.
  Grid through = g;
  through.borrowed = nullptr;
  through.source = &source;
  fn(through);
}

Grid converted(const occseg_map* map, int threads) {
  if (!map->is_view) return map->grid;
  const occseg_map::View& v = map->view;
  Grid copy;
  copy.dims = map->grid.dims;
  copy.voxel_size = map->grid.voxel_size;
  copy.origin = map->grid.origin;
  occseg::resize_for_fill(copy.p, copy.dims.count(), 0);
  convert(copy.p.data(), copy.dims, v.data, v.dtype, v.strides, v.flags, threads);
  return copy;
}

// occseg_map_from_buffer(_flags). The dtype is passed on by reference: a copy would read it as
// the enum type, undefined for a value out of its range (UBSan's enum check; enum_value()).
static int map_from_buffer(occseg_map** out, const void* data, const occseg_dtype& dtype, const size_t dims[3],
                           const ptrdiff_t strides[3], double voxel_size, uint32_t flags) {
  return guard("occseg_map_from_buffer", [&] {
    auto m = checked_map(out, data, dtype, dims, strides, voxel_size, flags);
    occseg::resize_for_fill(m->grid.p, m->grid.dims.count(), 0);
    convert(m->grid.p.data(), m->grid.dims, m->view.data, m->view.dtype, m->view.strides, flags);
    m->view = occseg_map::View();
    *out = m.release();
  });
}

}  // namespace occseg::capi

extern "C" {

int occseg_map_from_buffer_flags(occseg_map** out, const void* data, occseg_dtype dtype, const size_t dims[3],
                                 const ptrdiff_t strides[3], double voxel_size, uint32_t flags) {
  return occseg::capi::map_from_buffer(out, data, dtype, dims, strides, voxel_size, flags);
}

int occseg_map_view_buffer(occseg_map** out, const void* data, occseg_dtype dtype, const size_t dims[3],
                           const ptrdiff_t strides[3], double voxel_size, uint32_t flags) {
  return guard("occseg_map_view_buffer", [&] {
    auto m = checked_map(out, data, dtype, dims, strides, voxel_size, flags);
    m->is_view = true;
    if (dense_f32(*m)) m->grid.borrowed = reinterpret_cast<const float*>(m->view.data);
    *out = m.release();
  });
}

int occseg_map_from_buffer(occseg_map** out, const void* data, occseg_dtype dtype, const size_t dims[3],
                           const ptrdiff_t strides[3], double voxel_size) {
  return occseg::capi::map_from_buffer(out, data, dtype, dims, strides, voxel_size, OCCSEG_IMPORT_STRICT);
}

// By extension, through the registry (capi/plugins.cpp): .npy and .nrrd are built-in plugins.
int occseg_map_read(occseg_map** out, const char* path) { return occseg_map_read_options(out, path, nullptr); }

int occseg_map_write(const occseg_map* map, const char* path) { return occseg_map_write_options(map, path, nullptr); }

void occseg_map_free(occseg_map* map) { delete map; }

int occseg_map_dims(const occseg_map* map, size_t dims[3]) {
  return guard("occseg_map_dims", [&] {
    require(map, "map");
    require(dims, "dims");
    dims_out(map->grid.dims, dims);
  });
}

int occseg_map_voxel_size(const occseg_map* map, double* out) {
  return guard("occseg_map_voxel_size", [&] {
    require(map, "map");
    require(out, "out");
    *out = map->grid.voxel_size;
  });
}

int occseg_map_set_voxel_size(occseg_map* map, double voxel_size) {
  return guard("occseg_map_set_voxel_size", [&] {
    require(map, "map");
    check_voxel_size(voxel_size);
    occseg::check_geometry(map->grid.dims, voxel_size, map->grid.origin);
    map->grid.voxel_size = voxel_size;
  });
}

int occseg_map_origin(const occseg_map* map, double origin[3]) {
  return guard("occseg_map_origin", [&] {
    require(map, "map");
    require(origin, "origin");
    std::copy(map->grid.origin.begin(), map->grid.origin.end(), origin);
  });
}

int occseg_map_set_origin(occseg_map* map, const double origin[3]) {
  return guard("occseg_map_set_origin", [&] {
    require(map, "map");
    require(origin, "origin");
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(origin[k]))
        throw Error(Status::bad_value, "origin[" + std::to_string(k) + "] = " + number(origin[k], 6) + " is not finite");
    occseg::check_geometry(map->grid.dims, map->grid.voxel_size, {origin[0], origin[1], origin[2]});
    std::copy(origin, origin + 3, map->grid.origin.begin());
  });
}

int occseg_map_values(const occseg_map* map, float* out, size_t count) {
  return guard("occseg_map_values", [&] {
    require(map, "map");
    require(out, "out");
    const std::size_t n = map->grid.dims.count();
    if (count < n)
      throw Error(Status::out_of_range, "count " + std::to_string(count) + " is smaller than the " +
                                            std::to_string(n) + " voxels of the map");
    if (map->is_view) {  // straight from the buffer, checked as a copy would be
      const occseg_map::View& v = map->view;
      convert(out, map->grid.dims, v.data, v.dtype, v.strides, v.flags);
    } else {
      std::copy(map->grid.p.begin(), map->grid.p.end(), out);
    }
  });
}

}  // extern "C"

