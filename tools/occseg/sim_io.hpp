// Files of a simulated scene (written by `occseg simulate`, read by `occseg evaluate` and
// `occseg figures`) and the presentation of scores as JSON and text.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"
#include "occseg/segment.hpp"
#include "occseg/sim/metrics.hpp"
#include "occseg/sim/scanner.hpp"
#include "occseg/sim/truth.hpp"

namespace occseg::cli {

// Creates `dir` (and its parents) if missing; Error(io) naming it when that fails or it is not a directory.
void make_directory(const std::string& dir);

// Writes DIR/map.npy (float32 [z, y, x]), DIR/truth_state.npy (uint8 [z, y, x], occseg::State),
// DIR/truth_objects.npy (uint8, or uint16 beyond 255 objects, [z, y, x]) and DIR/scene.json,
// staged `into` the caller's set; without one, the four replace their old versions together
// (all four or none, the old ones untouched on failure).
void write_simulation(const std::string& dir, const sim::Scene& scene, const sim::ScanConfig& config,
                      const Grid& map, const sim::Truth& truth, StagedFiles* into = nullptr);

// The description written to scene.json.
nlohmann::json scene_json(const sim::Scene& scene, const sim::ScanConfig& config, const sim::Truth& truth);

struct TruthDir {
  sim::Truth truth;
  std::vector<std::string> object_names;  // from scene.json when present, index = id - 1
  std::string scene;                      // scene name, "" when unknown
  double voxel_size = 1.0;
};

// Reads DIR/truth_state.npy, DIR/truth_objects.npy and (optionally) DIR/scene.json. Throws
// Error(io/format/bad_dims/bad_value) naming the file and the problem.
TruthDir read_truth(const std::string& dir);

// A uint32 (or uint16/uint8) label volume [z, y, x] that must have `dims`.
LabelArray read_labels(const std::string& path, const Dims& dims);

// The state of each segment from a segments.json of `occseg segment` (index = id; ids must be
// 0..N-1). Throws Error(format) naming the file and the entry.
std::vector<State> read_segment_states(const std::string& path);

// The scored methods: "paper" and "default" (occseg::segment with that preset), "baseline"
// (sim::threshold_segmentation) and "ideal" (6-connected components of the ideal state itself:
// the fragmentation a perfect labelling would show). keep_stages as in occseg::segment.
Result run_method(const std::string& method, const Grid& map, const sim::Truth& truth, int threads,
                  bool keep_stages = false);
const std::vector<std::string>& method_names();

// Segment states of a Result, index = id.
std::vector<State> segment_states(const Result& r);

nlohmann::json scores_json(const sim::Scores& s, const std::vector<std::string>& object_names);

// A text table with one column per scored method.
std::string scores_table(const std::vector<std::string>& methods, const std::vector<sim::Scores>& scores,
                         const std::vector<std::string>& object_names);

}  // namespace occseg::cli
