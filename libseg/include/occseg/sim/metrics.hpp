// Scores of a segmentation against a simulated scene's ground truth (docs/experiments.md).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "occseg/params.hpp"
#include "occseg/sim/truth.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg::sim {

struct ObjectScore {
  std::uint16_t id = 0;
  std::uint64_t voxels = 0;         // voxels of its solid (truth.objects == id)
  std::uint64_t labelled_free = 0;  // of those, labelled free (unsafe)
  std::uint64_t surface = 0;        // ideal-occupied voxels attributed to it (its seen surface)
  std::uint64_t surface_found = 0;  // of those, labelled occupied
  std::uint32_t segments = 0;       // occupied segments with a voxel attributed to it
  // Share of its attributed occupied-labelled voxels that lie in the largest of those segments:
  // 1 when the object is one segment, whatever crumbs of noise sit beside it.
  double largest_share = 0;
};

struct Scores {
  std::uint64_t voxels = 0;
  double accuracy = 0;                           // share of voxels whose state is the ideal state
  std::array<double, 3> iou{};                   // per occseg::State; 1 when neither side has it
  std::array<std::uint64_t, 3> truth_voxels{};   // ideal state counts
  std::array<std::uint64_t, 3> labelled_voxels{};
  std::uint64_t object_voxels = 0, object_free = 0;    // voxels inside solids; labelled free
  std::uint64_t unknown_voxels = 0, unknown_free = 0;  // ideal-unknown voxels; labelled free
  double object_free_share = 0;   // object_free / object_voxels (0 when no object voxel)
  double unknown_free_share = 0;  // unknown_free / unknown_voxels
  std::uint32_t segments = 0;
  std::array<std::uint32_t, 3> segments_by_state{};
  std::uint32_t spanning_segments = 0;  // occupied segments attributed to two or more objects
  std::uint32_t stray_segments = 0;     // occupied segments attributed to no object
  std::vector<ObjectScore> objects;     // ids 1..max id in truth.objects
};

// Attributes every voxel within `reach` face-steps of a solid to the nearest one (breadth-first
// from all solid voxels at once; ties go to the solid reached first in voxel order); 0 beyond.
std::vector<std::uint16_t> attribute_to_objects(const Dims& dims, const std::vector<std::uint16_t>& objects, int reach);

// Scores labels (segment id per voxel, x fastest) whose segment `id` has state
// segment_states[id]. Occupied segments are attributed to objects through their voxels'
// attribution with `reach` (default 3 voxels: three standard deviations of the range noise at
// the default 4 cm voxels). Throws Error(bad_dims) when sizes differ, Error(out_of_range) naming the voxel
// when a label has no segment, Error(bad_value) for a truth state above 2.
Scores score_segmentation(const Truth& truth, const LabelArray& labels,
                          const std::vector<State>& segment_states, int reach = 3);

}  // namespace occseg::sim
