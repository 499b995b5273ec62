#include "map_input.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <iostream>
#include <memory>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/geometry.hpp"
#include "occseg/map_yaml.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/registry.hpp"
#ifdef OCCSEG_HAVE_PCL
#include "occseg/pcd.hpp"
#endif
#ifdef OCCSEG_HAVE_OCTOMAP
#include "occseg/octomap_file.hpp"
#include "occseg/octomap_segments.hpp"
#endif
#if defined(OCCSEG_HAVE_PCL) || defined(OCCSEG_HAVE_OCTOMAP)
#include "occseg/scan_options.hpp"
#endif

namespace occseg::cli {

namespace {

std::string extension(const std::string& path) {
  const std::size_t dot = path.rfind('.'), slash = path.rfind('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

// The input options and the formats each applies to (the help's lists; docs/cli.md): an option
// given for another format is a usage error naming it and its formats, whatever its value, never
// an option accepted and ignored. A plugin's format takes --voxel-size (its reader's option
// voxel_size) and nothing else.
void check_options_apply(const MapInputOptions& o, const std::string& ext, bool plugin) {
  struct Rule {
    const char* option;
    bool given;
    std::vector<std::string> formats;
    bool plugins;
  };
  const Rule rules[] = {
      {"--voxel-size", o.voxel_size.has_value(), {".npy", ".nrrd", ".pcd", ".graph", ".bt", ".ot"}, true},
      {"--bbox", o.bbox.has_value(), {".pcd", ".graph", ".bt", ".ot"}, false},
      {"--sensor-origin", o.sensor_origin.has_value(), {".pcd", ".graph"}, false},
      {"--sensor-orientation", o.sensor_orientation.has_value(), {".pcd", ".graph"}, false},
      {"--max-range", o.max_range >= 0, {".pcd", ".graph"}, false},
      {"--coarsen", !o.coarsen.empty(), {".bt", ".ot"}, false},
  };
  for (const Rule& r : rules) {
    if (!r.given || (plugin ? r.plugins : std::find(r.formats.begin(), r.formats.end(), ext) != r.formats.end()))
      continue;
    std::string list;
    for (std::size_t k = 0; k < r.formats.size(); ++k)
      list += (k == 0 ? "" : k + 1 == r.formats.size() && !r.plugins ? " and " : ", ") + r.formats[k];
    if (r.plugins) list += " and plugin formats";
    std::string why = plugin ? " (a plugin's format)" : "";
    if (ext == ".yaml" && std::string(r.option) == "--voxel-size") why = " (the YAML's resolution is the cell size)";
    throw Error(Status::invalid_argument, std::string(r.option) + " does not apply to " + ext + " input" + why +
                                              ": it applies to " + list + " only");
  }
}

// OctoMap tells stderr what it reads ("Reading octree type OcTree", "Done (23 nodes)"); the tool
// has its own progress and errors, so stderr (fd 2) goes to /dev/null while OctoMap reads.
class [[maybe_unused]] SilenceStderr {
 public:
  SilenceStderr() {
    std::cerr.flush();
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
  }
  ~SilenceStderr() {
    if (saved_ < 0) return;
    std::cerr.flush();
    std::fflush(stderr);
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
  }
  SilenceStderr(const SilenceStderr&) = delete;
  SilenceStderr& operator=(const SilenceStderr&) = delete;

 private:
  int saved_ = -1;
};

// A map whose box is out of range (check_geometry) could not be written as labels.nrrd.
void checked_geometry(const Grid& g, const std::string& path) {
  try {
    check_geometry(g);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
}

[[noreturn, maybe_unused]] void not_built(const std::string& ext, const char* lib) {
  throw Error(Status::unsupported, ext + " input needs " + lib + ", which this build of occseg lacks");
}

#if defined(OCCSEG_HAVE_PCL) || defined(OCCSEG_HAVE_OCTOMAP)
std::optional<Box> box_of(const MapInputOptions& o) {
  if (!o.bbox) return std::nullopt;
  const auto& b = *o.bbox;
  return Box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
}

ScanOptions scan_options(const MapInputOptions& o) {
  ScanOptions s;
  s.voxel_size = o.voxel_size.value_or(0.05);
  s.model.max_range = o.max_range;
  s.bbox = box_of(o);
  s.threads = o.threads;
  s.progress = o.progress;
  // Each half of the pose replaces its half of the stored one (the help's "default: stored pose").
  s.sensor_origin = o.sensor_origin;
  s.sensor_orientation = o.sensor_orientation;
  return s;
}
#endif

// numpy's name of an .npy dtype string.
std::string npy_type(const std::string& descr) {
  static const char* names[][2] = {{"<f4", "float32"}, {"<f8", "float64"}, {"|u1", "uint8"},
                                   {"<u1", "uint8"},   {"<u2", "uint16"},  {"<u4", "uint32"}};
  for (const auto& n : names)
    if (descr == n[0]) return n[1];
  return descr;
}

}  // namespace

bool have_octomap() {
#ifdef OCCSEG_HAVE_OCTOMAP
  return true;
#else
  return false;
#endif
}

bool is_octomap_input(const std::string& path) {
  const std::string e = extension(path);
  return e == ".bt" || e == ".ot" || e == ".graph";
}

bool write_octree_output(const std::string& path, const Grid& grid, const Result& result, StagedFiles* into,
                         std::array<double, 3>* shift) {
#ifdef OCCSEG_HAVE_OCTOMAP
  const OctreePlacement p = write_segments_octree(path, grid, result, into);
  if (shift) *shift = p.shift;
  return p.snapped;
#else
  (void)grid;
  (void)result;
  (void)into;
  (void)shift;
  not_built(path, "OctoMap (liboccseg_octomap)");
#endif
}

bool have_pcl() {
#ifdef OCCSEG_HAVE_PCL
  return true;
#else
  return false;
#endif
}

MapInput load_map(const std::string& path, const MapInputOptions& o) {
  const std::string ext = extension(path);
  MapInput in;
  const bool coarsen = !o.coarsen.empty();
  const bool builtin = ext == ".npy" || ext == ".nrrd" || ext == ".yaml" || ext == ".pcd" || ext == ".graph" ||
                       ext == ".bt" || ext == ".ot";
  if (builtin || find_reader(ext)) check_options_apply(o, ext, !builtin);
  if (ext == ".npy" || ext == ".nrrd") {
    in.kind = InputKind::volume;
    if (ext == ".npy") {
      NpyArray a;
      in.grid = read_npy_grid(path, o.voxel_size.value_or(1.0), &a, o.read_progress, o.threads);
      in.format = "NumPy .npy, " + npy_type(a.descr) + (a.big_endian ? " big-endian" : "") + (a.fortran_order ? ", Fortran order" : ", C order");
    } else {
      const NrrdVolume v = read_nrrd(path, o.read_progress);
      in.format = std::string("NRRD, ") + nrrd_type_name(v.type);
      if (!v.space.empty() && v.space != kNrrdDefaultSpace) in.format += ", " + v.space + " coordinates";
      in.grid = grid_from_nrrd(v, path);
      in.nrrd_space = v.space;
      if (o.voxel_size) {  // the file's spacing, overridden; keep the first voxel centre in place
        for (double& c : in.grid.origin) c += (in.grid.voxel_size - *o.voxel_size) / 2;
        in.grid.voxel_size = *o.voxel_size;
        checked_geometry(in.grid, path);
      }
    }
    return in;
  }
  if (ext == ".yaml") {  // a map_server / Nav2 map: its resolution and origin are in the file
    in.kind = InputKind::map2d;
    in.grid = read_map_yaml(path);
    in.format = "map_server map (.yaml + PGM image, " + std::to_string(in.grid.dims.nx) + " x " +
                std::to_string(in.grid.dims.ny) + " cells)";
    return in;
  }
  if (ext == ".pcd" || ext == ".graph") {
    in.kind = InputKind::cloud;
    if (ext == ".pcd") {
#ifdef OCCSEG_HAVE_PCL
      auto cloud = std::make_shared<PcdCloud>();
      in.grid = read_pcd(path, scan_options(o), cloud.get());
      in.format = "PCL point cloud (.pcd), fused by ray casting";
      in.point_shape = cloud->height > 1 ? std::vector<std::size_t>{cloud->height, cloud->width}
                                         : std::vector<std::size_t>{cloud->width * cloud->height};
      const int threads = o.threads;
      in.point_labels = [cloud, threads](const Grid& g, const Result& r) {
        return pcd_point_labels(*cloud, g, r, threads);
      };
      in.write_points_pcd = [cloud](const std::string& f, const std::vector<std::uint32_t>& labels, StagedFiles& s) {
        write_points_pcd(f, *cloud, labels, &s);
      };
#else
      not_built(ext, "PCL (liboccseg_pcl)");
#endif
    } else {
#ifdef OCCSEG_HAVE_OCTOMAP
      SilenceStderr quiet;
      in.grid = read_scan_graph(path, scan_options(o));
      in.format = "OctoMap scan graph (.graph), fused by ray casting";
#else
      not_built(ext, "OctoMap (liboccseg_octomap)");
#endif
    }
    return in;
  }
  if (ext == ".bt" || ext == ".ot") {
    in.kind = InputKind::tree;
#ifdef OCCSEG_HAVE_OCTOMAP
    OctreeOptions t;
    t.voxel_size = o.voxel_size.value_or(0.0);
    t.bbox = box_of(o);
    if (coarsen && o.coarsen != "max" && o.coarsen != "mean")
      throw Error(Status::invalid_argument, "--coarsen '" + o.coarsen + "' is not max or mean");
    t.coarsen = o.coarsen == "mean" ? Coarsen::mean : Coarsen::max;
    t.progress = o.read_progress;
    {
      SilenceStderr quiet;
      in.grid = read_octree_file(path, t);
    }
    in.format = std::string("OctoMap tree (") + ext + (ext == ".bt" ? ", maximum likelihood)" : ", log-odds)");
#else
    not_built(ext, "OctoMap (liboccseg_octomap)");
#endif
    return in;
  }
  if (find_reader(ext)) {  // a reader a plugin registered (occseg plugins lists them)
    std::vector<std::string> options;
    if (o.voxel_size) {
      char t[64];
      std::snprintf(t, sizeof t, "voxel_size=%.17g", *o.voxel_size);
      options.push_back(t);
    }
    in.grid = read_map(path, options);
    checked_geometry(in.grid, path);
    in.format = ext + " through a plugin reader";
    return in;
  }
  throw Error(Status::invalid_argument, "'" + path + "': unknown input type '" + ext +
                                            "' (use .npy, .nrrd, .yaml, .pcd, .graph, .bt, .ot or one a plugin reads)");
}

void write_cloud_output(const std::string& path, const Grid& grid, const Result& result, StagedFiles* into) {
#ifdef OCCSEG_HAVE_PCL
  write_segments_pcd(path, grid, result, StateSet(), into);
#else
  (void)grid;
  (void)result;
  (void)into;
  not_built(path, "PCL (liboccseg_pcl)");
#endif
}

}  // namespace occseg::cli
