// What `occseg segment` and `occseg demo` tell the user: a short text summary (segments per
// state, the largest objects with their boxes in metres, time per stage) or the same as JSON
// (--json), and the picture of the segmentation (segmentation.png).
#pragma once
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"
#include "occseg/segment.hpp"

namespace occseg::cli {

// A segmentation run as reported: the input, the grid it was computed on, the result, and the
// times of the steps around segment() (reading or fusing the input, writing the outputs).
struct RunReport {
  std::string input;    // file name, or a description for the demo
  std::string format;   // map_input's description of the input
  std::string preset;
  const Grid* grid = nullptr;
  const Result* result = nullptr;
  std::vector<StageTime> steps;   // "read", the pipeline stages, "write", ... in order
  std::vector<std::string> files; // written
  std::vector<std::string> removed; // earlier runs' outputs removed from the folder
  std::size_t top = 5;            // number of largest objects to list
};

// An occupied segment's box in metres: the outer faces of its voxels (min corner of the first,
// max corner of the last), from the grid's origin and voxel size.
struct MetricBox {
  std::array<double, 3> min{}, max{};
};
MetricBox metric_box(const Grid& grid, const Segment& s);

// The `top` occupied segments: objects first, then structure, then clutter, each largest first
// (ties: lower id first).
std::vector<const Segment*> largest_objects(const Result& r, std::size_t top);

// Segment counts per kind (index = Kind).
std::array<std::uint64_t, 5> segments_per_kind(const Result& r);

// Voxel counts per state (index = State).
std::array<std::uint64_t, 3> voxels_per_state(const Result& r);

void print_summary(std::ostream& out, const RunReport& run);
nlohmann::json summary_json(const RunReport& run);

// segmentation.png: orthogonal slices (up to four z levels, a y and an x slice through the
// largest object, or the middle when there is none, and the top view) through the map (grey),
// the segmentation (state colours, segment boundaries, each occupied segment in its palette
// colour, ids on the larger ones) and, when given, an ideal state (the demo's ground truth), with
// a legend. Slices, layout and scale: see docs/cli.md. `threads`: for the panels (the same file
// for any count).
void write_segmentation_png(const std::string& path, const std::string& title, const Grid& grid, const Result& r,
                            const std::vector<std::uint8_t>* truth_states = nullptr, StagedFiles* into = nullptr,
                            int threads = 1);

// scene.png: the occupied segments as shaded voxels seen obliquely from above, one colour per
// segment, with a scale bar and a legend of the largest segments (render_scene.hpp).
void write_scene_png(const std::string& path, const std::string& title, const Grid& grid, const Result& r,
                     StagedFiles* into = nullptr);

}  // namespace occseg::cli
