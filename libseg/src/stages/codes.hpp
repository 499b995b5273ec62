// Storage of texture codes (internal). segment() keeps the built-in operator's codes in the label
// array it allocates anyway, so codes may live in storage of another type: every access to them
// goes through code_t (util/aliasing.hpp).
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "stages/divide.hpp"
#include "util/aliasing.hpp"

namespace occseg::detail {

struct MapRowSink;  // pipeline/map_pass.hpp

// compute_texture() writing the codes into `codes` (grid.dims.count() entries) instead of a
// fresh array. Same codes, same errors. With `lbp_scratch` (grid.dims.count() bytes, any
// storage), the first pass parks the LBP codes there and the second reads them instead of the
// map. With `rows`, the first pass hands every row of the map to it right after the row's
// texture (while the row is in the cache), as MapRowSink says. A grid read through a source
// (Grid::source) is converted plane by plane into a ring of three planes per thread when
// `lbp_scratch` is given (the second pass then reads no map values); without it, whole into a
// float copy first.
void compute_texture_into(const Grid& grid, int contrast_bins, int threads, code_t* codes,
                          std::uint8_t* lbp_scratch = nullptr, const MapRowSink* rows = nullptr,
                          const kernels::Table& k = kernels::active());

// divide() on codes in any storage: `code_count` distinct codes (TextureMap::code_count()).
// faces_only: kNoTexture codes lie only on the map's outer faces (the built-in operator's codes;
// a plugin may leave any voxel without texture), so blocks inside are counted without a test.
std::vector<Block> divide_codes(const Grid& grid, const code_t* codes, int code_count, const Params& params,
                                bool faces_only, const kernels::Table& k);

}  // namespace occseg::detail
