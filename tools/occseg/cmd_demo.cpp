// `occseg demo` (and `occseg` without arguments): the main job on an embedded default. Simulates
// the paper's cone scene (320 x 320 x 128 voxels of 4 cm, planar scans, seed 1), segments it,
// scores the segmentation against the ground truth and writes everything to ./occseg-out/:
// the map and its truth, labels, segments, the pictures, the scores and a summary.
#include <chrono>
#include <cstdint>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "format.hpp"
#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/segment.hpp"
#include "occseg/segments_json.hpp"
#include "occseg/sim/metrics.hpp"
#include "occseg/sim/scanner.hpp"
#include "occseg/sim/truth.hpp"
#include "options.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "report.hpp"
#include "sim_io.hpp"

namespace occseg::cli {

namespace {

struct DemoArgs {
  std::string out_dir = "occseg-out", scene = "cone", mode = "planar";
  std::uint64_t seed = 1;
  std::vector<std::size_t> dims{320, 320, 128};
  double voxel_size = 0.04, max_range = 8.0;  // (no --max-range: the building's default)
  PipelineArgs pipeline;
  ReportArgs report;
};

// What the demo prints without --json: the summary, the scores and the files, explained.
void print_demo_summary(std::ostream& os, RunReport rep, const sim::Scene& scene, const sim::Scores& scores,
                        const std::string& dir, double voxel_size) {
  rep.files.clear();  // listed with explanations below
  const bool papers = scene.name == "cone" || scene.name == "cube" || scene.name == "cylinder";
  os << "occseg demo: the " << (papers ? "paper's " : "") << scene.name << " scene, simulated, segmented and scored\n";
  print_summary(os, rep);
  os << "scores against the ground truth: voxel accuracy " << percent(scores.accuracy) << ", IoU free "
     << fixed(scores.iou[0], 3) << ", unknown " << fixed(scores.iou[1], 3) << ", occupied " << fixed(scores.iou[2], 3)
     << "; object voxels labelled free " << percent(scores.object_free_share) << ", unknown voxels labelled free "
     << percent(scores.unknown_free_share) << "\n";
  const std::string d = dir + "/";
  os << "\nLook at " << d << "segmentation.png first. Everything is in " << d << ":\n"
     << "  segmentation.png   slices through the map, the segments and the ideal state\n"
     << "  scene.png          the occupied segments in 3D, one colour per segment\n"
     << "  segments.json      the segment table: state, kind, voxels, mean probability, box, centroid\n"
     << "  labels.npy         segment id per voxel, uint32 [z, y, x]; labels.nrrd for ParaView/3D Slicer\n"
     << "  map.npy            the simulated map, float32 [z, y, x]: try `occseg segment " << d
     << "map.npy --voxel-size " << voxel_size << " --out seg`\n"
     << "  truth_state.npy    the ideal state per voxel; truth_objects.npy, scene.json: the scene\n"
     << "  evaluation.txt     scores against the ground truth (evaluation.json: the same as JSON)\n"
     << "  summary.json       this summary as JSON\n"
     << "Next: occseg segment YOUR_MAP --out DIR   (occseg --help; docs/cli.md)\n";
}

int run(const DemoArgs& o) {
  install_interrupt_handlers();  // Ctrl-C cancels through the progress callbacks
  if (o.dims.size() != 3) throw Error(Status::invalid_argument, "--dims takes three numbers: NX NY NZ");
  Params params = make_params(o.pipeline);
  ProgressBar bar(stderr_is_terminal() && !o.report.quiet);
  params.progress = bar.segment_callback();
  const sim::Scene scene = sim::make_scene(o.scene, Dims{o.dims[0], o.dims[1], o.dims[2]}, o.voxel_size);
  sim::ScanConfig config;
  config.mode = scan_mode(o.mode);
  config.max_range = o.max_range;
  config.seed = o.seed;
  config.threads = o.pipeline.threads;
  config.progress = bar.callback("simulating scans");
  config.validate();
  OutputSet out(o.out_dir);

  std::vector<StageTime> steps;
  auto t = std::chrono::steady_clock::now();
  const Grid map = sim::simulate_map(scene, config);
  steps.push_back({"simulate", seconds_since(t)});
  bar.update("ground truth", 0);
  t = std::chrono::steady_clock::now();
  const sim::Truth truth = sim::ground_truth(scene, config);
  steps.push_back({"ground truth", seconds_since(t)});
  check_interrupted();
  const Result r = segment(map, params);
  steps.insert(steps.end(), r.timings.begin(), r.timings.end());
  bar.update("scoring", 0);
  t = std::chrono::steady_clock::now();
  const sim::Scores scores = sim::score_segmentation(truth, r.labels, segment_states(r));
  steps.push_back({"evaluate", seconds_since(t)});
  check_interrupted();

  t = std::chrono::steady_clock::now();
  const std::string preset = preset_name(params.preset);
  const std::string method = "segmentation (preset " + preset + ")";
  using Writer = std::function<void(const std::string&, StagedFiles&)>;
  const std::vector<std::pair<std::string, Writer>> files{
      {"segmentation.png",
       [&](const std::string& f, StagedFiles& staged) {
         const Dims& d = map.dims;
         write_segmentation_png(f,
                                "occseg demo: " + scene.name + " (" + sim::scan_mode_name(config.mode) + ", " +
                                    std::to_string(d.nx) + " x " + std::to_string(d.ny) + " x " +
                                    std::to_string(d.nz) + ", seed " + std::to_string(o.seed) + ", preset " + preset +
                                    ")",
                                map, r, &truth.state, &staged);
       }},
      {"scene.png",
       [&](const std::string& f, StagedFiles& staged) {
         write_scene_png(f, "occseg demo: " + scene.name + ", preset " + preset + ", occupied segments", map, r,
                         &staged);
       }},
      {"labels.npy", [&](const std::string& f, StagedFiles& s) { write_labels_npy(f, r.dims, r.labels, &s); }},
      {"labels.nrrd", [&](const std::string& f, StagedFiles& s) { NrrdWriteOptions gz;
         gz.gzip = true;
         write_labels_nrrd(f, map, r.labels, "", &s, gz); }},
      {"segments.json",
       [&](const std::string& f, StagedFiles& s) {
         const std::vector<OrientedBox> boxes = oriented_boxes(r, map.voxel_size, map.origin);
         write_file_atomically(
             f, [&](std::ostream& os) { write_segments_json(os, r, preset, {map.voxel_size, map.origin, &boxes}); }, &s);
       }},
      {"evaluation.json",
       [&](const std::string& f, StagedFiles& staged) {
         const nlohmann::json j{{"scene", scene.name},
                                {"method", method},
                                {"reach", 3},
                                {"scores", scores_json(scores, scene.objects)}};
         const std::string text = j.dump(1) + "\n";
         write_file_atomically(f, [&](std::ostream& s) { s << text; }, &staged);
       }},
      {"evaluation.txt",
       [&](const std::string& f, StagedFiles& staged) {
         const std::string text = "scene " + scene.name + ", scored against the ideal state (truth_state.npy)\n" +
                                  scores_table({method}, {scores}, scene.objects);
         write_file_atomically(f, [&](std::ostream& s) { s << text; }, &staged);
       }}};
  // map.npy, truth_state.npy, truth_objects.npy, scene.json: as `occseg simulate` writes them.
  bar.update("writing map and ground truth", 0);
  out.write({"map.npy", "truth_state.npy", "truth_objects.npy", "scene.json"},
            [&](StagedFiles& s) { write_simulation(out.dir(), scene, config, map, truth, &s); });
  for (std::size_t k = 0; k < files.size(); ++k) {
    bar.update("writing " + files[k].first, double(k) / double(files.size()));
    out.write(files[k].first, files[k].second);
  }
  RunReport rep;
  rep.input = "simulated " + scene.name + " scene";
  rep.format = std::string(sim::scan_mode_name(config.mode)) + " scans from " + std::to_string(scene.viewpoints.size()) +
               " viewpoints, seed " + std::to_string(o.seed);
  rep.preset = preset;
  rep.grid = &map;
  rep.result = &r;
  rep.top = o.report.top;
  steps.push_back({"write", seconds_since(t)});
  rep.steps = steps;
  rep.files = out.files();
  nlohmann::json summary = summary_json(rep);
  summary["evaluation"] = scores_json(scores, scene.objects);
  const std::string text = summary.dump(1) + "\n";
  out.write("summary.json", [&](const std::string& f, StagedFiles& staged) {
    write_file_atomically(f, [&](std::ostream& s) { s << text; }, &staged);
  });
  summary["files"].push_back(out.path("summary.json"));
  // Everything printed is made before the files are put in place, so running out of memory
  // here still leaves the old files; after the commit only writing to stdout can fail.
  set_activity("making the summary");
  std::ostringstream shown;
  if (o.report.json) shown << summary.dump(1) << "\n";
  else if (!o.report.quiet) print_demo_summary(shown, rep, scene, scores, out.dir(), o.voxel_size);
  const std::string printed = shown.str();
  set_activity("putting the output files in place");
  out.commit();
  bar.clear();
  std::cout << printed;
  return kOk;
}


}  // namespace

Runner add_demo(CLI::App& app) {
  auto o = std::make_shared<DemoArgs>();
  CLI::App* c = app.add_subcommand(
      "demo", "Simulate the paper's cone scene, segment and score it, write everything to ./occseg-out/ (the default)");
  c->add_option("--out,-o", o->out_dir, "output directory (default occseg-out; created if missing)");
  c->add_option("--scene", o->scene,
                "cone (default), cube, cylinder (the paper's), close, table, doorway, building (its defaults: --dims "
                "400 300 60 --voxel-size 0.05 --mode rings, 25 m range)")
      ->check(CLI::IsMember(sim::scene_names()));
  c->add_option("--seed", o->seed, "seed of the range noise (default 1)")->transform(whole_number(0, UINT64_MAX));
  c->add_option("--mode", o->mode,
                "planar (the paper's stack of planar scans; default), full3d or rings (a spinning multi-beam lidar)")
      ->check(CLI::IsMember({"planar", "full3d", "rings"}));
  c->add_option("--dims", o->dims, "map size NX NY NZ in voxels (default 320 320 128)")->expected(3)
      ->transform(whole_number(1, std::size_t(1) << 40));
  c->add_option("--voxel-size", o->voxel_size, "voxel edge in metres (default 0.04)")->check(positive_number());
  add_pipeline_options(c, o->pipeline);
  add_report_options(c, o->report);
  return [c, o]() -> int {
    if (!c->parsed()) return -1;
    apply_scene_defaults(*c, o->scene, o->dims, o->voxel_size, o->mode, o->max_range);
    return run(*o);
  };
}

}  // namespace occseg::cli
