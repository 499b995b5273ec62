// segment() with a label array to write into (internal: Context::recycle hands one over).
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/segment.hpp"

namespace occseg {

// Storage a context keeps from one segment() to the next besides the label array (whose pages
// are then in already): the labelling's run-start bits (1/8 byte per voxel), and the own states'
// bits when they were made outside the label array (1/8 byte per voxel each).
struct Workspace {
  std::vector<std::uint8_t> run_starts;
  // The own states (detail::OwnBits) when the label array cannot hold them (a plugin's texture,
  // maps a few voxels wide).
  std::vector<std::uint64_t> unknown_bits, occupied_bits;
};

// segment(grid, params, keep_stages), writing the labels into `labels`' storage: when it holds
// at least as many elements as the map has voxels, no fresh memory is allocated or paged in for
// them (every label is written). Scratch goes to `workspace` when given. The result is the same
// as segment()'s.
Result segment_into(const Grid& grid, const Params& params, bool keep_stages, LabelArray&& labels,
                    Workspace* workspace = nullptr);

namespace detail {
// Throws Error(unsupported) when a map of `voxels` voxels cannot have uint32 labels (2^32 - 1 or
// more): segment() asks before it allocates anything, label_components() again.
void check_labels_fit(std::size_t voxels);
// Hands the pages of freed buffers back to the system (glibc: malloc_trim; elsewhere nothing).
void release_freed_memory();
}  // namespace detail

}  // namespace occseg
