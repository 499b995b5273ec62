// The built-in map readers and writers (.npy, .nrrd; map_server .yaml maps are read only),
// registered as the plugin "builtin_io" through the plugin host table by register_builtin_io
// (builtin_io.hpp), so that occseg_map_read / occseg_map_write find them by extension like any
// plugin's.
#include "builtin_io.hpp"

#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <string>

#include "occseg/error.hpp"
#include "occseg/map_yaml.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/occseg_plugin.h"
#include "occseg/plugin_host.hpp"
#include "occseg/registry.hpp"
#include "nrrd_space.hpp"

namespace {

using occseg::Error;
using occseg::Grid;

// Runs `body`, turning occseg::Error into host->set_error plus its status.
template <class Body>
int guarded(const occseg_plugin_call* call, Body&& body) {
  try {
    body();
    return 0;
  } catch (const Error& e) {
    call->host->set_error(e.what());
    return static_cast<int>(e.status());
  } catch (const std::bad_alloc&) {
    call->host->set_error("out of memory");
    return OCCSEG_ENOMEM;
  } catch (const std::exception& e) {
    call->host->set_error(e.what());
    return OCCSEG_EINTERNAL;
  }
}

// Options of the built-in readers: only voxel_size (.npy, which stores none: default 1; .nrrd,
// overriding the file's spacing: `fallback` 0 there means "not given").
double voxel_size_option(const char* path, const char* const* options, bool allowed, double fallback = 1.0) {
  double v = fallback;
  for (const char* const* o = options; o && *o; ++o) {
    const char* eq = std::strchr(*o, '=');
    if (allowed && eq && std::strncmp(*o, "voxel_size", static_cast<size_t>(eq - *o)) == 0 && eq - *o == 10) {
      char* end = nullptr;
      v = std::strtod(eq + 1, &end);
      if (end == eq + 1 || *end || !(v > 0))
        throw Error(occseg::Status::invalid_argument, std::string("'") + path + "': option '" + *o +
                                                          "': voxel_size must be a positive number");
    } else {
      throw Error(occseg::Status::invalid_argument, std::string("'") + path + "': unknown option '" + *o + "'" +
                                                        (allowed ? " (known: voxel_size)" : " (this reader takes none)"));
    }
  }
  return v;
}

void deliver(const occseg_plugin_call* call, occseg_plugin_map_sink* sink, const Grid& g) {
  const size_t dims[3] = {g.dims.nx, g.dims.ny, g.dims.nz};
  float* values = nullptr;
  if (int rc = call->host->map_alloc(sink, dims, g.voxel_size, g.origin.data(), &values))
    throw Error(static_cast<occseg::Status>(rc), "map_alloc failed");
  std::memcpy(values, g.p.data(), g.p.size() * sizeof(float));
}

Grid grid_of(const occseg_plugin_grid* v) {
  Grid g;
  g.dims = occseg::Dims{v->dims[0], v->dims[1], v->dims[2]};
  g.voxel_size = v->voxel_size;
  for (int k = 0; k < 3; ++k) g.origin[k] = v->origin[k];
  g.p.assign(v->values, v->values + g.dims.count());
  return g;
}

int read_npy_map(const occseg_plugin_call* call, const char* path, const char* const* options, occseg_plugin_map_sink* sink) {
  return guarded(call, [&] {
    const double vs = voxel_size_option(path, options, true);
    // One pass from the file into the grid, checked; the grid itself is the map (no map_alloc copy).
    occseg::deliver_grid(sink, occseg::read_npy_grid(path, vs, nullptr, {}, static_cast<int>(call->threads)));
  });
}

int read_nrrd_map(const occseg_plugin_call* call, const char* path, const char* const* options, occseg_plugin_map_sink* sink) {
  return guarded(call, [&] {
    const double vs = voxel_size_option(path, options, true, 0.0);
    const occseg::NrrdVolume v = occseg::read_nrrd(path);
    Grid g = occseg::grid_from_nrrd(v, path);
    if (vs > 0) {  // as the command's --voxel-size: the file's spacing replaced, the first voxel centre kept
      for (double& c : g.origin) c += (g.voxel_size - vs) / 2;
      g.voxel_size = vs;
    }
    deliver(call, sink, g);
    occseg::capi::nrrd_space_slot() = v.space;  // the map keeps the file's space (occseg_map_read)
  });
}

int read_yaml_map(const occseg_plugin_call* call, const char* path, const char* const* options, occseg_plugin_map_sink* sink) {
  return guarded(call, [&] {
    voxel_size_option(path, options, false);
    deliver(call, sink, occseg::read_map_yaml(path));
  });
}

int write_npy_map(const occseg_plugin_call* call, const char* path, const occseg_plugin_grid* grid, const char* const* options) {
  return guarded(call, [&] {
    voxel_size_option(path, options, false);
    occseg::write_grid_npy(path, grid_of(grid));
  });
}

int write_nrrd_map(const occseg_plugin_call* call, const char* path, const occseg_plugin_grid* grid, const char* const* options) {
  return guarded(call, [&] {
    voxel_size_option(path, options, false);
    occseg::write_grid_nrrd(path, grid_of(grid), occseg::capi::nrrd_space_slot());
  });
}

int register_io(const occseg_plugin_host* host, occseg_plugin_registrar* r) {
  const occseg_plugin_reader readers[] = {
      {sizeof(occseg_plugin_reader), ".npy", "NumPy array [z, y, x] or [y, x]: f4, f8, u1, u2 (option voxel_size, default 1)",
       read_npy_map, nullptr},
      {sizeof(occseg_plugin_reader), ".nrrd",
       "NRRD volume (raw or ascii) with its spacing and origin (option voxel_size replaces the spacing)", read_nrrd_map,
       nullptr},
      {sizeof(occseg_plugin_reader), ".yaml",
       "ROS map_server / Nav2 2D map: YAML with a PGM image (P5 8/16-bit, P2), resolution, origin, thresholds",
       read_yaml_map, nullptr},
  };
  const occseg_plugin_writer writers[] = {
      {sizeof(occseg_plugin_writer), ".npy", "float32 NumPy array [z, y, x]", write_npy_map, nullptr},
      {sizeof(occseg_plugin_writer), ".nrrd", "float NRRD volume with spacing and origin", write_nrrd_map, nullptr},
  };
  for (const auto& x : readers)
    if (int rc = host->register_reader(r, &x)) return rc;
  for (const auto& x : writers)
    if (int rc = host->register_writer(r, &x)) return rc;
  return 0;
}

const occseg_plugin_descriptor kBuiltinIo = {
    OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof(occseg_plugin_descriptor), "builtin_io",
    OCCSEG_VERSION_STRING, "built-in map readers and writers (.npy, .nrrd; .yaml read)", register_io};

}  // namespace

void occseg::capi::register_builtin_io() {
  static std::once_flag once;
  std::call_once(once, [] { occseg::register_static_plugin(&kBuiltinIo); });
}

std::string& occseg::capi::nrrd_space_slot() {
  thread_local std::string space;
  return space;
}
