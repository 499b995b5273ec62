// `occseg figures --out DIR`: the experiments of docs/experiments.md in one command. For each
// scene: simulate, segment with both presets, the baseline and the ideal labelling, score them,
// and draw a picture like the paper's Figures 5-7 ((a) the map, (b) after segment creation, (c)
// after refinement, plus the default preset and the ideal state) and the default preset's occupied
// segments in 3D (as scene.png of `occseg segment`). Writes DIR/<scene>.png, DIR/<scene>-scene.png,
// DIR/results-<mode>.md and DIR/results-<mode>.json, all or none (OutputSet): a failure or Ctrl-C
// leaves the old files of DIR as they were.
#include <cstdint>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "format.hpp"
#include "options.hpp"
#include "stages/label.hpp"
#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/sim/scanner.hpp"
#include "occseg/sim/truth.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "render_png.hpp"
#include "render_scene.hpp"
#include "sim_io.hpp"

namespace occseg::cli {

namespace {

struct FiguresOptions {
  std::string out_dir, mode = "planar";
  std::vector<std::string> scenes;
  std::vector<std::size_t> dims{320, 320, 128};
  double voxel_size = 0.04;
  std::uint64_t seed = 1;
  int threads = 0;
  bool pictures = true;
};

// A share as a percentage, without the sign (the tables' headers carry it).
std::string pct(double v) { return fixed(100 * v, 2); }

// One markdown row per method.
std::string table_row(const std::string& scene, const std::string& method, const sim::Scores& s) {
  std::string segs, largest, found;
  for (const sim::ObjectScore& o : s.objects) {
    const std::string sep = segs.empty() ? "" : " / ";
    segs += sep + std::to_string(o.segments);
    largest += sep + pct(o.largest_share);
    found += sep + pct(o.surface ? double(o.surface_found) / double(o.surface) : 0.0);
  }
  std::ostringstream r;
  r << "| " << scene << " | " << method << " | " << pct(s.accuracy) << " | " << fixed(s.iou[0], 3) << " | "
    << fixed(s.iou[1], 3) << " | " << fixed(s.iou[2], 3) << " | " << pct(s.object_free_share) << " | "
    << pct(s.unknown_free_share) << " | " << s.segments << " (" << s.segments_by_state[0] << "/"
    << s.segments_by_state[1] << "/" << s.segments_by_state[2] << ") | " << segs << " | " << largest << " | " << found
    << " | " << s.spanning_segments << " |\n";
  return r.str();
}

int run(const FiguresOptions& o) {
  install_interrupt_handlers();  // Ctrl-C stops at the next simulated layer or method
  if (o.dims.size() != 3) throw Error(Status::invalid_argument, "--dims takes three numbers: NX NY NZ");
  sim::ScanConfig config;
  config.mode = o.mode == "full3d" ? sim::ScanMode::full3d : sim::ScanMode::planar;
  config.seed = o.seed;
  config.threads = o.threads;
  config.progress = [](double) { return interrupt_signal() == 0; };
  // Default: the room scenes of docs/experiments.md's figures; the building (its own dims, voxel
  // size and scan mode, `occseg simulate --scene building`) only when asked for.
  std::vector<std::string> scenes = o.scenes;
  if (scenes.empty())
    for (const std::string& n : sim::scene_names())
      if (n != "building") scenes.push_back(n);
  OutputSet out(o.out_dir);
  const Dims dims{o.dims[0], o.dims[1], o.dims[2]};
  std::ostringstream md;
  md << "Scenes of " << dims.nx << " x " << dims.ny << " x " << dims.nz << " voxels of " << o.voxel_size
     << " m, " << sim::scan_mode_name(config.mode) << " scans, seed " << o.seed
     << ". Per-object columns list the objects in scene order.\n\n"
     << "| scene | method | accuracy % | IoU free | IoU unknown | IoU occupied | object voxels free % | "
        "unknown voxels free % | segments (F/U/O) | occupied segments per object | share in largest % | "
        "seen surface found % | segments spanning 2+ objects |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  nlohmann::json all = nlohmann::json::array();
  for (const std::string& name : scenes) {
    set_activity("scene " + name + ": simulating and scoring");
    const sim::Scene scene = sim::make_scene(name, dims, o.voxel_size);
    const Grid map = sim::simulate_map(scene, config);
    const sim::Truth truth = sim::ground_truth(scene, config);
    nlohmann::json results = nlohmann::json::array();
    Result paper, dflt, ideal;
    for (const std::string& m : method_names()) {
      check_interrupted();
      Result r = run_method(m, map, truth, o.threads, m == "paper");
      const sim::Scores s = sim::score_segmentation(truth, r.labels, segment_states(r));
      md << table_row(name, m, s);
      results.push_back({{"method", m}, {"scores", scores_json(s, scene.objects)}});
      if (m == "paper") paper = std::move(r);
      else if (m == "default") dflt = std::move(r);
      else if (m == "ideal") ideal = std::move(r);
    }
    all.push_back({{"scene", name}, {"results", results}});
    std::cout << "scene " << name << ": scored paper, default, baseline, ideal" << std::flush;
    if (o.pictures) {
      LabelArray created_labels;
      std::vector<Segment> created_segments;
      label_components(paper.created_states, map, created_labels, created_segments);
      const std::vector<std::uint8_t> paper_states = voxel_states(paper), default_states = voxel_states(dflt);
      std::vector<render::Volume> rows(5);
      rows[0] = {"(a) map", dims, map.p.data(), nullptr, nullptr, false};
      rows[1] = {"(b) paper: created", dims, nullptr, paper.created_states.data(), created_labels.data(), false};
      rows[2] = {"(c) paper: refined", dims, nullptr, paper_states.data(), paper.labels.data(), true};
      rows[3] = {"(d) default preset", dims, nullptr, default_states.data(), dflt.labels.data(), true};
      rows[4] = {"(e) ideal state", dims, nullptr, truth.state.data(), ideal.labels.data(), true};
      std::vector<render::Slice> slices;
      for (const sim::SliceHint& h : scene.slices) slices.push_back({h.axis, h.index});
      render::FigureOptions fo;
      fo.title = "occseg: " + name + " (" + sim::scan_mode_name(config.mode) + ", " + std::to_string(dims.nx) + "x" +
                 std::to_string(dims.ny) + "x" + std::to_string(dims.nz) + ", seed " + std::to_string(o.seed) + ")";
      const std::string suffix = config.mode == sim::ScanMode::full3d ? "-full3d" : "";
      const std::string file = name + suffix + ".png";
      set_activity("scene " + name + ": writing " + file);
      out.write(file, [&](const std::string& f, StagedFiles& s) {
        render::write_png(f, render::render_figure(rows, slices, fo), &s);
      });
      std::cout << ", picture " << out.path(file);
      // The default preset's occupied segments in 3D, as `occseg segment` draws them (scene.png).
      const std::string scene_file = name + suffix + "-scene.png";
      render::SceneOptions so;
      so.title = "occseg: " + name + " (" + sim::scan_mode_name(config.mode) + "), default preset, occupied segments";
      out.write(scene_file, [&](const std::string& f, StagedFiles& s) {
        render::write_png(f, render::render_scene(dflt, o.voxel_size, so), &s);
      });
      std::cout << ", " << out.path(scene_file);
    }
    std::cout << "\n";
  }
  const std::string mode = sim::scan_mode_name(config.mode);
  const std::string table = md.str();
  set_activity("writing the results");
  out.write("results-" + mode + ".md", [&](const std::string& f, StagedFiles& s) {
    write_file_atomically(f, [&](std::ostream& os) { os << table; }, &s);
  });
  const std::string json = nlohmann::json{{"mode", mode},
                                          {"dims", {dims.nx, dims.ny, dims.nz}},
                                          {"voxel_size", o.voxel_size},
                                          {"seed", o.seed},
                                          {"scenes", all}}
                               .dump(1) +
                           "\n";
  out.write("results-" + mode + ".json", [&](const std::string& f, StagedFiles& s) {
    write_file_atomically(f, [&](std::ostream& os) { os << json; }, &s);
  });
  set_activity("putting the output files in place");
  out.commit();
  std::cout << table;
  return kOk;
}

}  // namespace

Runner add_figures(CLI::App& app) {
  auto o = std::make_shared<FiguresOptions>();
  CLI::App* c = app.add_subcommand("figures", "Simulate, segment and score the scenes; draw Figures 5-7");
  c->add_option("--out,-o", o->out_dir, "output directory (created if missing)")->required();
  c->add_option("--scene", o->scenes, "scene(s), repeatable (default: all but building)")->check(CLI::IsMember(sim::scene_names()));
  c->add_option("--mode", o->mode, "planar or full3d")->check(CLI::IsMember({"planar", "full3d"}));
  c->add_option("--dims", o->dims, "map size NX NY NZ (default 320 320 128)")->expected(3)
      ->transform(whole_number(1, std::size_t(1) << 40));
  c->add_option("--voxel-size", o->voxel_size, "voxel edge in metres (default 0.04)")->check(positive_number());
  c->add_option("--seed", o->seed, "seed of the range noise (default 1)")->transform(whole_number(0, UINT64_MAX));
  c->add_option("--threads", o->threads, "worker threads, 0 = all cores")->transform(whole_number(0, 1024));
  c->add_flag("!--no-pictures", o->pictures, "scores only");
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
