// `occseg evaluate --truth DIR ...`: scores segmentations of a simulated scene against its ground
// truth. Either an existing one (--labels and --segments from `occseg segment`), or the methods
// named by --method run on DIR/map.npy (paper, default, baseline, ideal or all of them side by side).
#include <cstdint>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "options.hpp"
#include "occseg/error.hpp"
#include "occseg/npy.hpp"
#include "occseg/segment.hpp"
#include "occseg/sim/metrics.hpp"
#include "sim_io.hpp"

namespace occseg::cli {

namespace {

struct EvaluateOptions {
  std::string truth, labels, segments, map, method = "all";
  bool json = false;
  int reach = 3, threads = 0;
};

int run(const EvaluateOptions& o) {
  if (o.labels.empty() != o.segments.empty())
    throw Error(Status::invalid_argument, "--labels and --segments go together");
  const TruthDir t = read_truth(o.truth);
  std::vector<std::string> methods;
  std::vector<sim::Scores> scores;
  if (!o.labels.empty()) {
    const LabelArray labels = read_labels(o.labels, t.truth.dims);
    methods.push_back("segmentation");
    scores.push_back(sim::score_segmentation(t.truth, labels, read_segment_states(o.segments), o.reach));
  } else {
    const std::string path = o.map.empty() ? o.truth + "/map.npy" : o.map;
    const Grid grid = grid_from_npy(read_npy(path), t.voxel_size, path);
    if (!(grid.dims == t.truth.dims)) throw Error(Status::bad_dims, "'" + path + "' does not have the ground truth's dims");
    const std::vector<std::string> wanted = o.method == "all" ? method_names() : std::vector<std::string>{o.method};
    for (const std::string& m : wanted) {
      const Result r = run_method(m, grid, t.truth, o.threads);
      methods.push_back(m);
      scores.push_back(sim::score_segmentation(t.truth, r.labels, segment_states(r), o.reach));
    }
  }
  if (o.json) {
    nlohmann::json res = nlohmann::json::array();
    for (std::size_t k = 0; k < methods.size(); ++k)
      res.push_back({{"method", methods[k]}, {"scores", scores_json(scores[k], t.object_names)}});
    std::cout << nlohmann::json{{"truth", o.truth}, {"scene", t.scene}, {"reach", o.reach}, {"results", res}}.dump(1)
              << "\n";
  } else {
    if (!t.scene.empty()) std::cout << "scene " << t.scene << "\n";
    std::cout << scores_table(methods, scores, t.object_names);
  }
  return kOk;
}

}  // namespace

Runner add_evaluate(CLI::App& app) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* c = app.add_subcommand("evaluate", "Score segmentations of a simulated scene against its ground truth");
  c->add_option("--truth,-t", o->truth, "directory written by `occseg simulate`")->required();
  c->add_option("--labels", o->labels, "labels.npy of a segmentation to score (with --segments)");
  c->add_option("--segments", o->segments, "segments.json of that segmentation");
  c->add_option("--method", o->method, "without --labels: paper, default, baseline, ideal or all (default)")
      ->check(CLI::IsMember({"paper", "default", "baseline", "ideal", "all"}));
  c->add_option("--map", o->map, "map to segment instead of TRUTH/map.npy");
  c->add_option("--reach", o->reach, "voxels within which an occupied voxel is attributed to an object (default 3)")
      ->transform(whole_number(0, 64));
  c->add_option("--threads", o->threads, "worker threads, 0 = all cores")->transform(whole_number(0, 1024));
  c->add_flag("--json", o->json, "print JSON instead of a table");
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
