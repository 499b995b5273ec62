// `occseg segment IN.npy --out DIR`: segment a map and write labels.npy and segments.json.
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/npy.hpp"
#include "occseg/segment.hpp"
#include "segments_json.hpp"

namespace occseg::cli {

namespace {

struct SegmentOptions {
  std::string input, out_dir, preset = "default";
  int threads = 0;
  double voxel_size = 1.0;
  std::vector<std::string> params;
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
  const Grid grid = grid_from_npy(read_npy(o.input), o.voxel_size, o.input);
  const Result r = segment(grid, params);
  make_dir(o.out_dir);
  // Both files are complete before either is renamed into place: a failure leaves neither.
  const std::string labels = o.out_dir + "/labels.npy", json = o.out_dir + "/segments.json";
  const std::string text = segments_json(r, preset_name(params.preset)).dump(1) + "\n";
  write_labels_npy(labels, r.dims, r.labels);
  try {
    write_file_atomically(json, [&](std::ostream& out) { out << text; });
  } catch (...) {
    std::remove(labels.c_str());
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
  c->add_option("input", o->input, "map file: .npy float32/float64/uint8/uint16 indexed [z, y, x]")->required();
  c->add_option("--out,-o", o->out_dir, "output directory (created if missing)")->required();
  c->add_option("--preset", o->preset, "paper or default")->check(CLI::IsMember({"paper", "default"}));
  c->add_option("--threads", o->threads, "worker threads, 0 = all cores")->check(CLI::Range(0, 1024));
  c->add_option("--voxel-size", o->voxel_size, "voxel edge in metres (for .npy input)")->check(CLI::PositiveNumber);
  c->add_option("--param", o->params, "name=value, repeatable (see docs/algorithm.md)");
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
