// The baseline the texture segmentation is compared with: every voxel takes the state of its own
// probability (the same state bounds as the pipeline), then equal states form 6-connected segments.
#pragma once
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/segment.hpp"

namespace occseg::sim {

// Labels, segment table and timings like occseg::segment(). Uses params.free_below and
// params.occupied_above only. Validates the map and the parameters first.
Result threshold_segmentation(const Grid& grid, const Params& params = Params::defaults());

}  // namespace occseg::sim
