// A slow, scalar, single-threaded reference of the whole pipeline: the straightforward loops the
// fast stages in libseg/src/ replaced (voxel by voxel, line by line, union-find labelling). The
// tests compare the fast pipeline against it bit for bit on random maps (test_reference.cpp).
// It shares no code with the library: only the public types (Grid, Params, Block, Segment,
// TextureMap) and the documented orders of its sums (docs/algorithm.md).
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"
#include "occseg/texture_codes.hpp"

namespace occseg::reference {

// z-planes per labelling slab: the documented order of the segment sums (label_components()).
constexpr std::size_t kSlab = 8;

// Texture codes of every voxel, computed one texture unit (section 2.2) at a time.
TextureMap texture(const Grid& grid, int contrast_bins);
// The G-statistic in the library's documented summation order (docs/algorithm.md, section 2).
double g_statistic(const std::uint32_t* s, const std::uint32_t* m, std::size_t bins);
// Hierarchical division: histograms counted voxel by voxel for every octant that is examined.
std::vector<Block> divide(const Grid& grid, const TextureMap& texture, const Params& params);
// MOP state of every leaf painted per voxel.
std::vector<std::uint8_t> create(const Grid& grid, const std::vector<Block>& blocks, const Params& params);
// Refinement steps 1 and 2, one line at a time.
void refine_unknown(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params);
void refine_boundaries(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params);
// The default preset's per-voxel rules, with the opening done by per-line prefix sums.
void apply_voxel_rules(std::vector<std::uint8_t>& states, const Grid& grid, const Params& params);
// The default preset's surface band (rule 10), voxel by voxel: a free voxel no 3 x 3 x 3 cube of
// free voxels centred in the map (its voxels outside the map counting as free) holds, with an occupied and an unknown voxel each
// within params.surface_band face steps (taxicab distance), becomes occupied.
void apply_surface_band(std::vector<std::uint8_t>& states, const Dims& dims, const Params& params);
// Union-find labelling and the segment table, statistics summed in scan order; occupied voxels
// 26-connected when `occupied26`, everything else 6-connected.
void label(const std::vector<std::uint8_t>& states, const Grid& grid, LabelArray& labels,
           std::vector<Segment>& segments, bool occupied26 = false);

struct Output {
  std::vector<Block> blocks;
  std::vector<std::uint8_t> created;  // states after creation
  std::vector<std::uint8_t> refined;  // states before labelling
  LabelArray labels;
  std::vector<Segment> segments;
};
Output segment(const Grid& grid, const Params& params);

}  // namespace occseg::reference
