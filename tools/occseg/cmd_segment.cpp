// `occseg segment IN --out DIR`: segment a map (.npy .nrrd .pcd .graph .bt .ot, see map_input)
// and write labels.npy, labels.nrrd, segments.json, plus map.nrrd for inputs that were not
// grids and segments.pcd for point clouds.
#include <sys/stat.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/segment.hpp"
#include "map_input.hpp"
#include "segments_json.hpp"

namespace occseg::cli {

namespace {

struct SegmentOptions {
  std::string input, out_dir, preset = "default";
  int threads = 0;
  double voxel_size = 0;  // 0: not given (each input kind has its default, see map_input.hpp)
  std::vector<std::string> params;
  std::vector<double> bbox, sensor_origin, sensor_orientation;
  double max_range = -1;
  std::string coarsen = "max";
};

void make_dir(const std::string& dir) {
  if (::mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
    throw Error(Status::io, "cannot create '" + dir + "': " + std::strerror(errno));
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw Error(Status::io, "'" + dir + "' is not a directory");
}

int run(const SegmentOptions& o) {
  Params params;
  set_param(params, "preset", o.preset);
  for (const std::string& kv : o.params) {
    const std::size_t eq = kv.find('=');
    if (eq == std::string::npos)
      throw Error(Status::invalid_argument, "--param '" + kv + "' is not name=value");
    set_param(params, kv.substr(0, eq), kv.substr(eq + 1));
  }
  params.threads = o.threads;
  params.validate();
  MapInputOptions in;
  if (o.voxel_size > 0) in.voxel_size = o.voxel_size;
  if (!o.bbox.empty()) in.bbox = std::array<double, 6>{o.bbox[0], o.bbox[1], o.bbox[2], o.bbox[3], o.bbox[4], o.bbox[5]};
  if (!o.sensor_origin.empty())
    in.sensor_origin = std::array<double, 3>{o.sensor_origin[0], o.sensor_origin[1], o.sensor_origin[2]};
  if (!o.sensor_orientation.empty())
    in.sensor_orientation = std::array<double, 4>{o.sensor_orientation[0], o.sensor_orientation[1],
                                                  o.sensor_orientation[2], o.sensor_orientation[3]};
  in.max_range = o.max_range;
  in.coarsen = o.coarsen;
  in.threads = o.threads;
  const MapInput input = load_map(o.input, in);
  const Grid& grid = input.grid;
  const Result r = segment(grid, params);
  make_dir(o.out_dir);
  // Each file is complete before it is renamed into place, and a failure removes the ones
  // already written: the directory gets all outputs or none.
  const std::string text = segments_json(r, preset_name(params.preset)).dump(1) + "\n";
  std::vector<std::string> written;
  auto emit = [&](const std::string& name, const std::function<void(const std::string&)>& write) {
    write(o.out_dir + "/" + name);
    written.push_back(o.out_dir + "/" + name);
  };
  try {
    emit("labels.npy", [&](const std::string& f) { write_labels_npy(f, r.dims, r.labels); });
    emit("labels.nrrd", [&](const std::string& f) { write_labels_nrrd(f, grid, r.labels); });
    if (input.kind != InputKind::volume) emit("map.nrrd", [&](const std::string& f) { write_grid_nrrd(f, grid); });
    if (input.kind == InputKind::cloud && have_pcl())
      emit("segments.pcd", [&](const std::string& f) { write_cloud_output(f, grid, r); });
    emit("segments.json", [&](const std::string& f) {
      write_file_atomically(f, [&](std::ostream& out) { out << text; });
    });
  } catch (...) {
    for (const std::string& f : written) std::remove(f.c_str());
    throw;
  }
  std::size_t per_state[3] = {0, 0, 0};
  for (const Segment& s : r.segments) ++per_state[static_cast<int>(s.state)];
  std::cout << r.segments.size() << " segments (" << per_state[0] << " free, " << per_state[1]
            << " unknown, " << per_state[2] << " occupied) written to " << o.out_dir << "\n";
  return kOk;
}

}  // namespace

Runner add_segment(CLI::App& app) {
  auto o = std::make_shared<SegmentOptions>();
  CLI::App* c = app.add_subcommand("segment", "Segment a probabilistic occupancy map");
  c->add_option("input", o->input,
                "map file: .npy/.nrrd grid (float32/float64/uint8/uint16), .pcd cloud, .graph OctoMap scan graph, "
                ".bt/.ot OctoMap tree")->required();
  c->add_option("--out,-o", o->out_dir, "output directory (created if missing)")->required();
  c->add_option("--preset", o->preset, "paper or default")->check(CLI::IsMember({"paper", "default"}));
  c->add_option("--threads", o->threads, "worker threads, 0 = all cores")->check(CLI::Range(0, 1024));
  c->add_option("--voxel-size", o->voxel_size,
                "voxel edge in metres (.npy: default 1; .nrrd: the file's spacing; .pcd/.graph: default 0.05; "
                ".bt/.ot: a multiple of the tree resolution, default the resolution)")->check(CLI::PositiveNumber);
  c->add_option("--bbox", o->bbox, "grid box XMIN YMIN ZMIN XMAX YMAX ZMAX in metres (.pcd .graph .bt .ot; default: fitted)")
      ->expected(6);
  c->add_option("--sensor-origin", o->sensor_origin, "X Y Z: sensor position for .pcd/.graph (default: stored pose)")
      ->expected(3);
  c->add_option("--sensor-orientation", o->sensor_orientation, "W X Y Z: sensor rotation quaternion for .pcd/.graph")
      ->expected(4);
  c->add_option("--max-range", o->max_range, "metres; longer returns mark free space only (.pcd/.graph)")
      ->check(CLI::PositiveNumber);
  c->add_option("--coarsen", o->coarsen, "max or mean: rule for .bt/.ot at a coarser voxel size")
      ->check(CLI::IsMember({"max", "mean"}));
  c->add_option("--param", o->params, "name=value, repeatable (see docs/algorithm.md)");
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
