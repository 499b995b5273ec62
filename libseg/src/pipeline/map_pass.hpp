// The fused first pass over the map: the texture's first pass reads each row of the map, and the
// creation adds the row to its 8^3 cells' sums and writes its voxels' own states as bits while
// the row is still in the cache, so that neither reads the map (the call's largest array) again.
#pragma once
#include <cstddef>
#include <cstdint>

namespace occseg {
struct Grid;
struct Params;
struct TextureOperator;
namespace kernels {
struct Table;
}
}  // namespace occseg

namespace occseg::detail {

class CellRows;  // stages/own_states.hpp

// Planes of the map the texture's first pass keeps on one thread: every group of planes it gives
// a thread is a multiple of kMapPassPlanes deep and starts at a multiple of it, so that all rows
// of a group of kMapPassPlanes planes (a layer of the creation's cells) reach the sink on one
// thread, in scan order.
constexpr std::size_t kMapPassPlanes = 8;

// What the texture's first pass hands each row of the map (y, z) to right after it has read it
// (faces included, every row once): row(self, y, z, values), on the thread that read it, with the
// row's nx values as the pass read them (in the map, or converted from a grid's MapSource into
// the pass's scratch: valid during the call only).
struct MapRowSink {
  void (*row)(void* self, std::size_t y, std::size_t z, const float* values) = nullptr;
  void* self = nullptr;
};

// Runs the built-in texture operator `op` (op.native_into, into `codes` with `scratch` as there)
// with every row of the map added to `cells` as the first pass reads it; returns the number of
// distinct codes.
int fused_map_pass(const TextureOperator& op, const Grid& grid, const Params& params, const kernels::Table& k,
                   std::uint16_t* codes, std::uint8_t* scratch, CellRows& cells);

}  // namespace occseg::detail
