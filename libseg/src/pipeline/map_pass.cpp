// The fused first pass over the map (map_pass.hpp).
#include "pipeline/map_pass.hpp"

#include "occseg/registry.hpp"
#include "stages/create.hpp"
#include "stages/own_states.hpp"

namespace occseg::detail {

static_assert(kMapPassPlanes % kMeanCell == 0, "a cell's planes must stay on one thread");

int fused_map_pass(const TextureOperator& op, const Grid& grid, const Params& params, const kernels::Table& k,
                   std::uint16_t* codes, std::uint8_t* scratch, CellRows& cells) {
  MapRowSink sink;
  sink.row = [](void* self, std::size_t y, std::size_t z, const float* values) {
    static_cast<CellRows*>(self)->add_row(y, z, values);
  };
  sink.self = &cells;
  return op.native_into(grid, params, k, codes, scratch, &sink);
}

}  // namespace occseg::detail
