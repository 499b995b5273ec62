// `occseg segment IN --out DIR`: segment a map (.npy .nrrd .pcd .graph .bt .ot, see map_input)
// and write labels.npy, labels.nrrd, segments.json, segmentation.png and scene.png, plus map.nrrd for inputs
// that were not grids, segments.pcd for point clouds and segmentation.pgm + segmentation.yaml (a
// map_server map) for 2D maps (nz = 1), points.labels.npy and points.pcd (labels on the input
// points) for .pcd clouds, segments.ot (a ColorOcTree) for OctoMap inputs; segments.ply on
// request; then a summary on stdout (text or --json). All outputs or
// none (OutputSet): until every file is complete the old files of DIR stay as they were; a
// failure, out of memory or Ctrl-C removes the new files' temporaries.
#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/map_yaml.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/segment.hpp"
#include "occseg/segments_json.hpp"
#include "occseg/voxel_mesh.hpp"
#include "map_input.hpp"
#include "options.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "report.hpp"

namespace occseg::cli {

namespace {

struct SegmentArgs {
  std::string input, out_dir;
  PipelineArgs pipeline;
  InputArgs in;
  ReportArgs report;
};

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Outputs written only on request. Issue 27's --outputs LIST decides which; until it is merged
// none is requested, and the on-request writers below are only reached through it.
bool requested(const std::string& name) {
  (void)name;
  return false;
}

std::string base_name(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The title of scene.png: the input, the map's size and voxel, the preset.
std::string picture_title(const std::string& input, const Grid& grid, const std::string& preset) {
  const Dims& d = grid.dims;
  std::ostringstream title;
  title << "occseg segment " << base_name(input) << "  (" << d.nx << " x " << d.ny << " x " << d.nz << " voxels of "
        << grid.voxel_size << " m, preset " << preset << ")";
  return title.str();
}

using Writer = std::function<void(const std::string&, StagedFiles&)>;
using FileList = std::vector<std::pair<std::string, Writer>>;

// The outputs, in the order written: a name and its writer. Out of line: GCC 12 inlines the
// vector's growth into run() and then warns wrongly (-Warray-bounds) about its empty array.
[[gnu::noinline]] void add_file(FileList& files, const char* name, Writer write) {
  files.emplace_back(name, std::move(write));
}

int run(const SegmentArgs& o) {
  install_interrupt_handlers();  // Ctrl-C cancels through the progress callbacks
  Params params = make_params(o.pipeline);
  ProgressBar bar(stderr_is_terminal() && !o.report.quiet);
  params.progress = bar.segment_callback();
  MapInputOptions in = make_input_options(o.in, o.pipeline.threads);
  in.progress = bar.callback("fusing scans");
  OutputSet out(o.out_dir);  // first, so an unusable directory fails before the long part

  std::vector<StageTime> steps;
  auto t = std::chrono::steady_clock::now();
  bar.update("reading " + base_name(o.input), 0);
  const MapInput input = load_map(o.input, in);
  steps.push_back({"read", since(t)});
  check_interrupted();
  const Grid& grid = input.grid;
  const Result r = segment(grid, params);
  steps.insert(steps.end(), r.timings.begin(), r.timings.end());

  t = std::chrono::steady_clock::now();
  const std::string preset = preset_name(params.preset);
  FileList files;
  add_file(files, "labels.npy",
                     [&](const std::string& f, StagedFiles& s) { write_labels_npy(f, r.dims, r.labels, &s); });
  // In the input's space (an LPS volume's labels in LPS, lying on it in 3D Slicer).
  add_file(files, "labels.nrrd", [&](const std::string& f, StagedFiles& s) {
    write_labels_nrrd(f, grid, r.labels, input.nrrd_space, &s);
  });
  if (input.kind != InputKind::volume)
    add_file(files, "map.nrrd", [&](const std::string& f, StagedFiles& s) { write_grid_nrrd(f, grid, "", &s); });
  if (input.kind == InputKind::cloud && have_pcl())
    add_file(files, "segments.pcd",
                       [&](const std::string& f, StagedFiles& s) { write_cloud_output(f, grid, r, &s); });
  // Labels back on the input points (issue 26), for .pcd inputs; computed once for both files.
  std::vector<std::uint32_t> point_labels;
  if (input.point_labels) {
    point_labels = input.point_labels(grid, r);
    // default (outputs-plan): uint32, one label per input point in file order ([height, width]
    // for an organized cloud), UINT32_MAX for NaN points
    add_file(files, "points.labels.npy", [&](const std::string& f, StagedFiles& s) {
      write_npy(f, "<u4", input.point_shape, point_labels.data(), point_labels.size() * sizeof(std::uint32_t), &s);
    });
  }
  if (input.write_points_pcd)  // on request (outputs-plan): the input cloud with a label field
    add_file(files, "points.pcd", [&](const std::string& f, StagedFiles& s) {
      input.write_points_pcd(f, point_labels, s);
    });
  std::vector<std::uint8_t> states;
  if (grid.dims.nz == 1) {  // a 2D map: also as the PGM/YAML pair map_server (a 2D planner) loads
    states = voxel_states(r);
    add_file(files, "segmentation.pgm",
                       [&](const std::string& f, StagedFiles& s) { write_state_pgm(f, grid.dims, states, &s); });
    add_file(files, "segmentation.yaml", [&](const std::string& f, StagedFiles& s) {
      write_map_yaml(f, "segmentation.pgm", grid, &s);
    });
  }
  add_file(files, "segments.json", [&](const std::string& f, StagedFiles& s) {
    // With the map's frame and each segment's oriented box, in metres (occseg/boxes.hpp).
    const std::vector<OrientedBox> boxes = oriented_boxes(r, grid.voxel_size, grid.origin);
    write_file_atomically(
        f, [&](std::ostream& os) { write_segments_json(os, r, preset, {grid.voxel_size, grid.origin, &boxes}); }, &s);
  });
  // segments.ot (an OctoMap ColorOcTree coloured by segment, for octovis and RViz): default for
  // OctoMap inputs (.bt/.ot/.graph), on request (--outputs) for any other input.
  std::array<double, 3> ot_shift{0, 0, 0};
  bool ot_snapped = false;
  if (have_octomap() && (is_octomap_input(o.input) || requested("segments.ot")))
    add_file(files, "segments.ot", [&](const std::string& f, StagedFiles& s) {
      ot_snapped = write_octree_output(f, grid, r, &s, &ot_shift);
    });
  // segments.ply (the occupied segments' surfaces, binary PLY, colour per vertex, segment per
  // face, metres): on request (--outputs).
  if (requested("segments.ply"))
    add_file(files, "segments.ply", [&](const std::string& f, StagedFiles& s) {
      write_segments_ply(f, r, grid.voxel_size, grid.origin, &s);
    });
  add_file(files, "segmentation.png", [&](const std::string& f, StagedFiles& s) {
    const Dims& d = grid.dims;
    write_segmentation_png(f,
                           "occseg segment " + base_name(o.input) + "  (" + std::to_string(d.nx) + " x " +
                               std::to_string(d.ny) + " x " + std::to_string(d.nz) + ", preset " + preset + ")",
                           grid, r, nullptr, &s);
  });
  // Default output (issue 25): the 3D picture of the occupied segments.
  const std::string scene_title = picture_title(o.input, grid, preset);
  add_file(files, "scene.png", [&](const std::string& f, StagedFiles& s) { write_scene_png(f, scene_title, grid, r, &s); });
  for (std::size_t k = 0; k < files.size(); ++k) {
    bar.update("writing " + files[k].first, double(k) / double(files.size()));
    out.write(files[k].first, files[k].second);
  }
  steps.push_back({"write", since(t)});

  RunReport rep;
  rep.input = o.input;
  rep.format = input.format;
  rep.preset = preset;
  rep.grid = &grid;
  rep.result = &r;
  rep.steps = steps;
  rep.files = out.files();
  rep.top = o.report.top;
  // The summary is made before the files are put in place, so running out of memory here still
  // leaves the old files; after the commit only writing it to stdout can fail.
  set_activity("making the summary");
  std::string text;
  if (o.report.json) {
    text = summary_json(rep).dump(1) + "\n";
  } else if (!o.report.quiet) {
    std::ostringstream s;
    print_summary(s, rep);
    text = s.str();
  }
  set_activity("putting the output files in place");
  out.commit();
  bar.clear();
  if (ot_snapped && !o.report.quiet) {
    char note[256];
    std::snprintf(note, sizeof note,
                  "occseg: note: segments.ot: the map's origin is not a whole number of %g m voxels from the world "
                  "origin, as OctoMap's lattice needs; the tree is moved by (%g, %g, %g) m\n",
                  grid.voxel_size, ot_shift[0], ot_shift[1], ot_shift[2]);
    std::cerr << note;
  }
  std::cout << text;
  return kOk;
}

}  // namespace

Runner add_segment(CLI::App& app) {
  auto o = std::make_shared<SegmentArgs>();
  CLI::App* c = app.add_subcommand("segment", "Segment a probabilistic occupancy map; write labels, segments, a picture");
  c->add_option("input", o->input,
                "map file: .npy/.nrrd grid (float32/float64/uint8/uint16), .yaml map_server 2D map, .pcd cloud, "
                ".graph OctoMap scan graph, .bt/.ot OctoMap tree")
      ->required();
  c->add_option("--out,-o", o->out_dir, "output directory (created if missing)")->required();
  add_pipeline_options(c, o->pipeline);
  add_input_options(c, o->in);
  add_report_options(c, o->report);
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
