// How many voxels of a segment each row of its box holds, counted on the threads: the walks that
// pick every n / k-th member of a segment in scan order (rule 5's and rule 11's samples) then
// skip the rows without a pick unread, instead of counting them one after the other.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/planes.hpp"
#include "occseg/grid.hpp"
#include "occseg/parallel.hpp"
#include "occseg/segment.hpp"

namespace occseg {

// Row r of seg's box (r = (z - z0) * rows_y + y - y0, the box's rows in scan order) holds
// counts[r] voxels labelled s.
inline std::vector<std::uint32_t> box_row_members(const Dims& d, const std::uint32_t* labels, const Segment& seg,
                                                  std::uint32_t s, int threads, const kernels::PlanesKernels& k) {
  const std::size_t x0 = seg.bbox_min[0], x1 = seg.bbox_max[0] + 1;
  const std::size_t rows_y = std::size_t(seg.bbox_max[1] - seg.bbox_min[1]) + 1;
  const std::size_t rows = rows_y * (std::size_t(seg.bbox_max[2] - seg.bbox_min[2]) + 1);
  std::vector<std::uint32_t> counts(rows);
  parallel_for(rows, threads, [&](std::size_t r0, std::size_t r1) {
    std::vector<std::uint64_t> bits((x1 - x0 + 63) / 64);
    for (std::size_t r = r0; r < r1; ++r) {
      const std::size_t y = seg.bbox_min[1] + r % rows_y, z = seg.bbox_min[2] + r / rows_y;
      counts[r] = static_cast<std::uint32_t>(k.row_members(labels + d.nx * (y + d.ny * z), x0, x1, s, bits.data()));
    }
  });
  return counts;
}

}  // namespace occseg
