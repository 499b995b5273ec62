// The whole pipeline: grid -> texture -> division -> segment creation -> refinement -> labels.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

// Runs the pipeline. Validates the map (dims, values) and the parameters first; throws
// occseg::Error with a status and a message naming the problem.
Result segment(const Grid& grid, const Params& params = Params::defaults(), bool keep_stages = false);

// State of every voxel (values of occseg::State), from labels and the segment table.
std::vector<std::uint8_t> voxel_states(const Result& result);

}  // namespace occseg
