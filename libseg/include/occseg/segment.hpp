// The whole pipeline: grid -> texture -> division -> segment creation -> refinement -> labels.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/components.hpp"
#include "occseg/divide.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

struct StageTime {
  std::string stage;
  double seconds;
};

struct Result {
  Dims dims;
  LabelArray labels;                  // segment id per voxel, x fastest (not zeroed on allocation)
  std::vector<Segment> segments;      // index = id
  std::vector<StageTime> timings;
  // Filled only when segment() is asked to keep stages (for pictures of Figures 5-7):
  std::vector<Block> blocks;                   // leaves of the hierarchical division
  std::vector<std::uint8_t> created_states;    // states after segment creation, before refinement
};

// Runs the pipeline. Validates the map (dims, values) and the parameters first; throws
// occseg::Error with a status and a message naming the problem.
Result segment(const Grid& grid, const Params& params = Params::defaults(), bool keep_stages = false);

// State of every voxel (values of occseg::State), from labels and the segment table.
std::vector<std::uint8_t> voxel_states(const Result& result);

}  // namespace occseg
