// segment() with a label array to write into (internal: Context::recycle hands one over).
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/segment.hpp"

namespace occseg {

// segment(grid, params, keep_stages), writing the labels into `labels`' storage: when it holds
// at least as many elements as the map has voxels, no fresh memory is allocated, zero-filled or
// paged in for them (every label is written). The result is the same as segment()'s.
Result segment_into(const Grid& grid, const Params& params, bool keep_stages, std::vector<std::uint32_t>&& labels);

}  // namespace occseg
