// One thread's reader of a map's values by runs of a row: where they lie, or, for a grid read
// through a source (grid.hpp's MapSource), converted into the reader's own row of scratch, so
// that no stage needs the whole map as floats.
#pragma once
#include <cstddef>
#include <vector>

#include "occseg/grid.hpp"

namespace occseg::detail {

class MapRows {
 public:
  explicit MapRows(const Grid& g) : g_(&g), scratch_(g.source ? g.dims.nx : 0) {}
  // The values of voxels [i, i + n) of one row (n <= nx), valid until the next call. The map has
  // been checked: a value the source refuses throws its error.
  const float* run(std::size_t i, std::size_t n) {
    if (!g_->source) return g_->values() + i;
    if (!g_->source->read(i, n, scratch_.data())) g_->source->fail();
    return scratch_.data();
  }
  const float* row(std::size_t y, std::size_t z) { return run(g_->index(0, y, z), g_->dims.nx); }

 private:
  const Grid* g_;
  std::vector<float> scratch_;
};

}  // namespace occseg::detail
