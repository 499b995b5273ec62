// What segment() returns: the labels, the segment table, the stages' times, and (on request) the
// blocks of the division and the states of the creation.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

// An axis-aligned box of voxels, [lo, hi) on each axis.
struct Block {
  std::uint32_t lo[3];
  std::uint32_t hi[3];
  std::uint64_t volume() const {
    return std::uint64_t(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  }
};

// What a segment is in the scene (docs/algorithm.md, "Presets", rule 9): free and unknown follow
// the state; an occupied segment is structure (it lies mostly on a support plane: a floor, a wall,
// a table top), an object, or clutter (fewer than min_object_voxels voxels, nothing to act on).
// The values are those of occseg_kind in the C ABI.
enum class Kind : std::uint8_t { free = 0, unknown = 1, structure = 2, object = 3, clutter = 4 };
const char* kind_name(Kind k);

// (kind beside state, in the padding before voxels: 72 bytes, not 80; the labelling's table of
// a noisy map holds 250 k of them at the pipeline's peak.)
struct Segment {
  std::uint32_t id = 0;
  State state = State::unknown;
  Kind kind = Kind::unknown;                       // set by segment() (assign_kinds)
  std::uint64_t voxels = 0;
  double mop = 0;                                  // mean occupancy probability of its voxels
  std::array<std::uint32_t, 3> bbox_min{0, 0, 0};  // voxel indices, inclusive
  std::array<std::uint32_t, 3> bbox_max{0, 0, 0};
  std::array<double, 3> centroid{0, 0, 0};         // mean voxel index (x, y, z)
};
static_assert(sizeof(Segment) == 72, "Segment: kind belongs in the padding after state");

struct StageTime {
  std::string stage;
  double seconds;
};

struct Result {
  Dims dims;
  double voxel_size = 1.0;                // the map's frame (Grid): metres per voxel edge, and
  std::array<double, 3> origin{0, 0, 0};  // the world position of the corner of voxel (0, 0, 0)
  LabelArray labels;                  // segment id per voxel, x fastest (not zeroed on allocation)
  std::vector<Segment> segments;      // index = id
  std::vector<StageTime> timings;
  // Filled only when segment() is asked to keep stages (for pictures of Figures 5-7):
  std::vector<Block> blocks;                   // leaves of the hierarchical division
  std::vector<std::uint8_t> created_states;    // states after segment creation, before refinement
};

}  // namespace occseg
