// `occseg segment IN --out DIR`: segment a map (.npy .nrrd .pcd .graph .bt .ot, see map_input)
// and write its outputs (kOutputs: a compact set by default, the rest on request with --outputs);
// then a summary on stdout (text or --json). All outputs or none (OutputSet): until every file is
// complete the old files of DIR stay as they were; a failure, out of memory or Ctrl-C removes the
// new files' temporaries. Files of kOutputs's names that an earlier run left in DIR and this run
// did not write are removed in the same commit, so DIR then holds this run's set only.
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "format.hpp"
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
  std::string outputs = "default";
  PipelineArgs pipeline;
  InputArgs in;
  ReportArgs report;
};

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

// Every file `occseg segment` can write, the order of writing. `by_default`: written without
// --outputs; the others on request (--outputs NAME,... or all). The names are also what a later
// run into the same DIR removes when it does not write them again.
struct OutputInfo {
  const char* name;
  bool by_default;
  const char* when;  // for whom it applies, in --help and in the error for one that does not
};
constexpr OutputInfo kOutputs[] = {
    {"labels.nrrd", true, "always"},          // segment id per voxel, gzip-encoded NRRD (issue 27)
    {"segments.json", true, "always"},
    {"segmentation.png", true, "always"},
    {"segmentation.pgm", true, "2D maps (nz = 1)"},
    {"segmentation.yaml", true, "2D maps (nz = 1)"},
    {"labels.npy", false, "always"},          // on request
    {"map.nrrd", false, "inputs that are not grids (.pcd .graph .bt .ot .yaml)"},  // on request
    {"segments.pcd", false, ".pcd/.graph inputs"},                                 // on request
    {"scene.png", true, "always"},                    // the occupied segments in 3D (issue 25)
    {"points.labels.npy", true, ".pcd inputs"},       // a label per input point (issue 26)
    {"points.pcd", false, ".pcd inputs"},             // on request: the input cloud with a label field
    // An OctoMap ColorOcTree by segment: by default for OctoMap inputs (.bt .ot .graph), on request
    // for any other (Output::default_here).
    {"segments.ot", false, "every input (by default for .bt/.ot/.graph)"},
    {"segments.ply", false, "always"},                // on request: the occupied segments' surfaces
};

std::string output_names() {
  std::string s;
  for (const OutputInfo& o : kOutputs) s += (s.empty() ? "" : ", ") + std::string(o.name);
  return s;
}

const OutputInfo* find_output(const std::string& name) {
  for (const OutputInfo& o : kOutputs)
    if (name == o.name) return &o;
  return nullptr;
}

// --outputs LIST: file names of kOutputs, `default` (the default set) and `all` (every output
// that applies to the input), comma-separated. Error(invalid_argument), exit 1, for any other.
struct OutputChoice {
  bool all = false, defaults = false;
  std::vector<std::string> names;
};
OutputChoice parse_outputs(const std::string& list) {
  OutputChoice c;
  std::size_t at = 0;
  for (;;) {
    const std::size_t comma = list.find(',', at);
    std::string item = list.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (item == "all") c.all = true;
    else if (item == "default") c.defaults = true;
    else if (find_output(item)) c.names.push_back(item);
    else
      throw Error(Status::invalid_argument,
                  "--outputs: " + (item.empty() ? std::string("an empty name") : "'" + item + "'") +
                      " is not an output of occseg segment (" + output_names() + ", default or all)");
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  return c;
}

// The same file (device and inode), so that an input that lives in DIR under an output's name is
// never removed as an earlier run's file.
bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

bool is_regular_file(const std::string& p) {
  struct stat st {};
  return ::lstat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// --- a map too large for this machine fails before it is allocated -----------------------------

// Bytes per voxel of `occseg segment` at its peak: the map (4), the labels (4) and the stages'
// scratch beyond them (docs/performance.md: at most 6 with the labels), rounded up; the fusion
// of a cloud (5 per voxel beside the map) stays below it.
constexpr double kBytesPerVoxel = 10;

// Memory the process can still take: MemAvailable, and what RLIMIT_AS leaves above the address
// space in use. 0 when neither is known (no check then).
double available_bytes() {
  double avail = 0;
  if (std::FILE* f = std::fopen("/proc/meminfo", "r")) {
    char line[256];
    while (std::fgets(line, sizeof line, f))
      if (std::strncmp(line, "MemAvailable:", 13) == 0) avail = std::strtod(line + 13, nullptr) * 1024;
    std::fclose(f);
  }
  rlimit as {};
  if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    double used = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
      unsigned long pages = 0;
      if (std::fscanf(f, "%lu", &pages) == 1) used = double(pages) * double(::sysconf(_SC_PAGESIZE));
      std::fclose(f);
    }
    const double left = std::max(0.0, double(as.rlim_cur) - used);
    avail = avail > 0 ? std::min(avail, left) : left;
  }
  return avail;
}

struct SizeCheckContext {
  std::string input;
  enum { grid, cloud, tree } kind = grid;
  double voxel_size = 0;  // clouds: the voxel size in use
  std::size_t approved = 0;  // the largest count passed: a later check of the same map passes too
};
SizeCheckContext g_size;

std::string bytes_text(double b) {
  char t[32];
  if (b >= 1e9) std::snprintf(t, sizeof t, "%.1f GB", b / 1e9);
  else std::snprintf(t, sizeof t, "%.0f MB", std::ceil(b / 1e6));
  return t;
}

void check_map_size(const Dims& d) {
  const std::size_t n = d.count();
  if (n <= g_size.approved) return;
  const double need = double(n) * kBytesPerVoxel, avail = available_bytes();
  if (avail <= 0 || need <= avail) {
    g_size.approved = n;
    return;
  }
  char activity[160];
  current_activity(activity, sizeof activity);
  std::string m = std::string("out of memory while ") + (*activity ? activity : "reading " + g_size.input) + ": the map has " +
                  std::to_string(d.nx) + " x " + std::to_string(d.ny) + " x " + std::to_string(d.nz) + " = " +
                  std::to_string(n) + " voxels, which need " + bytes_text(need) + " (" + std::to_string(int(kBytesPerVoxel)) +
                  " bytes per voxel), and " + bytes_text(avail) + " are available";
  // Voxels scale with the cube of the voxel size (the square for a one-layer map).
  const double scale = std::pow(need / avail, d.nz == 1 ? 0.5 : 1.0 / 3.0) * 1.01;
  if (g_size.kind == SizeCheckContext::cloud) {
    char t[64];
    const double v = g_size.voxel_size * scale, step = std::pow(10.0, std::floor(std::log10(v)) - 1);
    std::snprintf(t, sizeof t, "%g", std::ceil(v / step) * step);
    m += std::string(": a voxel size of ") + t + " m or more would fit (--voxel-size)";
  } else if (g_size.kind == SizeCheckContext::tree) {
    m += ": a voxel size " + std::to_string(static_cast<long>(std::ceil(scale))) +
         " times the one used or more would fit (--voxel-size, a multiple of the tree's resolution)";
  } else {
    m += " (the file holds that many voxels: segment it on a machine with more memory, or a part of it)";
  }
  throw Error(Status::no_memory, m);
}

int run(const SegmentArgs& o) {
  install_interrupt_handlers();  // Ctrl-C cancels through the progress callbacks
  const OutputChoice choice = parse_outputs(o.outputs);  // a usage error before the long part
  Params params = make_params(o.pipeline);
  ProgressBar bar(stderr_is_terminal() && !o.report.quiet);
  params.progress = bar.segment_callback();
  MapInputOptions in = make_input_options(o.in, o.pipeline.threads);
  in.progress = bar.callback("fusing scans");
  in.read_progress = bar.callback("reading " + base_name(o.input));
  OutputSet out(o.out_dir);  // first, so an unusable directory fails before the long part
  {
    std::string ext = o.input.substr(std::min(o.input.size(), o.input.rfind('.') == std::string::npos ? o.input.size() : o.input.rfind('.')));
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    g_size.input = base_name(o.input);
    g_size.kind = ext == ".pcd" || ext == ".graph" ? SizeCheckContext::cloud
                  : ext == ".bt" || ext == ".ot"   ? SizeCheckContext::tree
                                                   : SizeCheckContext::grid;
    g_size.voxel_size = in.voxel_size.value_or(0.05);
    set_grid_size_check(check_map_size);
  }

  std::vector<StageTime> steps;
  auto t = std::chrono::steady_clock::now();
  bar.update("reading " + base_name(o.input), 0);
  const MapInput input = load_map(o.input, in);
  steps.push_back({"read", seconds_since(t)});
  check_interrupted();
  const Grid& grid = input.grid;
  const Result r = segment(grid, params);
  steps.insert(steps.end(), r.timings.begin(), r.timings.end());

  t = std::chrono::steady_clock::now();
  const std::string preset = preset_name(params.preset);
  // Each output: its name, whether it applies to this input, and its writer (given the progress
  // of its own bytes, 0..1).
  using Writer = std::function<void(const std::string&, StagedFiles&, const IoProgress&)>;
  struct Output {
    std::string name;
    bool applies;
    Writer write;
    bool default_here = false;  // in the default set for this input although not in every one's
    int cost = 0;  // the larger, the earlier it starts (write_concurrently)
  };
  const bool map2d = grid.dims.nz == 1;
  std::vector<std::uint8_t> states;  // for the 2D pair, made only when it is written
  NrrdWriteOptions gz;
  gz.gzip = true;
  gz.threads = o.pipeline.threads;
  std::vector<Output> files;
  // In the input's space (an LPS volume's labels in LPS, lying on it in 3D Slicer).
  files.push_back({"labels.nrrd", true, [&](const std::string& f, StagedFiles& s, const IoProgress& p) {
                     NrrdWriteOptions w = gz;
                     w.progress = p;
                     write_labels_nrrd(f, grid, r.labels, input.nrrd_space, &s, w);
                   }});
  files.push_back({"segments.json", true, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     // With the map's frame and each segment's oriented box, in metres (occseg/boxes.hpp).
                     const std::vector<OrientedBox> boxes = oriented_boxes(r, grid.voxel_size, grid.origin);
                     write_file_atomically(
                         f,
                         [&](std::ostream& os) {
                           write_segments_json(os, r, preset, {grid.voxel_size, grid.origin, &boxes});
                         },
                         &s);
                   }});
  files.push_back({"segmentation.png", true, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     const Dims& d = grid.dims;
                     write_segmentation_png(f,
                                            "occseg segment " + base_name(o.input) + "  (" + std::to_string(d.nx) +
                                                " x " + std::to_string(d.ny) + " x " + std::to_string(d.nz) +
                                                ", preset " + preset + ")",
                                            grid, r, nullptr, &s, o.pipeline.threads);
                   }});
  // A 2D map: also as the PGM/YAML pair map_server (a 2D planner) loads.
  files.push_back({"segmentation.pgm", map2d, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     if (states.empty()) states = voxel_states(r);
                     write_state_pgm(f, grid.dims, states, &s);
                   }});
  files.push_back({"segmentation.yaml", map2d, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     write_map_yaml(f, "segmentation.pgm", grid, &s);
                   }});
  files.push_back({"labels.npy", true, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     write_labels_npy(f, r.dims, r.labels, &s);
                   }});
  files.push_back({"map.nrrd", input.kind != InputKind::volume,
                   [&](const std::string& f, StagedFiles& s, const IoProgress& p) {
                     NrrdWriteOptions w = gz;
                     w.progress = p;
                     write_grid_nrrd(f, grid, "", &s, w);
                   }});
  files.push_back({"segments.pcd", input.kind == InputKind::cloud && have_pcl(),
                   [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     write_cloud_output(f, grid, r, &s);
                   }});
  const std::string scene_title = picture_title(o.input, grid, preset);
  files.push_back({"scene.png", true, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     write_scene_png(f, scene_title, grid, r, &s);
                   }});
  // Labels back on the input points (issue 26), for .pcd inputs; computed once for both files.
  // (Both writers may run at the same time: the first to ask computes them, the other waits.)
  std::vector<std::uint32_t> point_labels;
  std::once_flag point_labels_once;
  auto labels_of_points = [&]() -> const std::vector<std::uint32_t>& {
    std::call_once(point_labels_once, [&] { point_labels = input.point_labels(grid, r); });
    return point_labels;
  };
  // uint32, one label per input point in file order ([height, width] for an organized cloud),
  // UINT32_MAX for NaN points.
  files.push_back({"points.labels.npy", bool(input.point_labels),
                   [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     const std::vector<std::uint32_t>& l = labels_of_points();
                     write_npy(f, "<u4", input.point_shape, l.data(), l.size() * sizeof(std::uint32_t), &s);
                   }});
  files.push_back({"points.pcd", bool(input.point_labels) && bool(input.write_points_pcd),
                   [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     input.write_points_pcd(f, labels_of_points(), s);
                   }});
  // segments.ot (a ColorOcTree coloured by segment, for octovis and RViz's OctoMap display).
  std::array<double, 3> ot_shift{0, 0, 0};
  bool ot_snapped = false;
  files.push_back({"segments.ot", have_octomap(),
                   [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     ot_snapped = write_octree_output(f, grid, r, &s, &ot_shift);
                   },
                   is_octomap_input(o.input)});
  // segments.ply: the occupied segments' surfaces, binary PLY, colour per vertex, segment per face.
  files.push_back({"segments.ply", true, [&](const std::string& f, StagedFiles& s, const IoProgress&) {
                     write_segments_ply(f, r, grid.voxel_size, grid.origin, &s);
                   }});
  // Which to start first when they are written at the same time: the longest (measured on the
  // benchmark maps, docs/performance.md), so that no thread waits alone for a late long one.
  for (Output& f : files)
    for (const auto& [name, cost] : {std::pair<const char*, int>{"segments.ot", 9}, {"labels.npy", 8}, {"map.nrrd", 8},
                                     {"segments.pcd", 8}, {"points.pcd", 8}, {"segmentation.png", 7},
                                     {"labels.nrrd", 6}, {"segments.ply", 5}, {"segments.json", 4}, {"scene.png", 3}})
      if (f.name == name) f.cost = cost;
  // What to write: named ones must apply (a usage error otherwise, before anything is written).
  for (const std::string& n : choice.names) {
    const auto it = std::find_if(files.begin(), files.end(), [&](const Output& f) { return f.name == n; });
    if (it != files.end() && !it->applies)
      throw Error(Status::invalid_argument, "--outputs: " + n + " does not apply to this input (it is written for " +
                                                find_output(n)->when + ")");
  }
  std::vector<const Output*> chosen;
  for (const Output& f : files) {
    const OutputInfo* info = find_output(f.name);
    const bool named = std::find(choice.names.begin(), choice.names.end(), f.name) != choice.names.end();
    const bool by_default = (info && info->by_default) || f.default_here;
    if (f.applies && (choice.all || named || (choice.defaults && by_default))) chosen.push_back(&f);
  }
  // The files are independent: written at the same time, the costliest started first. The bar
  // shows the share of all of them done, under the name of the file that reported last.
  std::vector<double> done(chosen.size(), 0.0);
  std::mutex done_mutex;
  std::vector<OutputSet::Job> jobs;
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    const std::string label = "writing " + chosen[k]->name;
    jobs.push_back({chosen[k]->name, [&, k, label](const std::string& f, StagedFiles& s) {
                      const IoProgress progress = [&, k, label](double fraction) {
                        double total = 0;
                        {
                          std::lock_guard<std::mutex> lock(done_mutex);
                          done[k] = fraction;
                          for (double d : done) total += d;
                        }
                        return bar.update(label, total / double(done.size()));
                      };
                      set_activity(label);
                      progress(0.0);
                      chosen[k]->write(f, s, progress);
                      progress(1.0);
                    }});
  }
  std::vector<std::size_t> start(chosen.size());
  for (std::size_t k = 0; k < start.size(); ++k) start[k] = k;
  std::stable_sort(start.begin(), start.end(),
                   [&](std::size_t a, std::size_t b) { return chosen[a]->cost > chosen[b]->cost; });
  out.write_concurrently(jobs, start, o.pipeline.threads);
  bar.update("writing", 1.0);
  // Files an earlier run left under an output's name, not written now: removed in the commit
  // (regular files only; the input itself never).
  for (const OutputInfo& info : kOutputs) {
    const std::string p = out.path(info.name);
    const bool written = std::any_of(chosen.begin(), chosen.end(), [&](const Output* f) { return f->name == info.name; });
    if (!written && is_regular_file(p) && !same_file(p, o.input)) out.remove(info.name);
  }
  steps.push_back({"write", seconds_since(t)});

  RunReport rep;
  rep.input = o.input;
  rep.format = input.format;
  rep.preset = preset;
  rep.grid = &grid;
  rep.result = &r;
  rep.steps = steps;
  rep.files = out.files();
  rep.removed = out.removed();
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
  c->add_option("--outputs", o->outputs,
                "comma-separated files to write: default (" + std::string("labels.nrrd, segments.json, "
                "segmentation.png, scene.png; 2D maps also segmentation.pgm + .yaml; .pcd inputs "
                "points.labels.npy; OctoMap inputs segments.ot), all (every file that applies "
                "to the input), or names among: ") + output_names())
      ->type_name("LIST");
  add_pipeline_options(c, o->pipeline);
  add_input_options(c, o->in);
  add_report_options(c, o->report);
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
