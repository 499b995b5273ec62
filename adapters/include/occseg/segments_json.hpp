// segments.json, the segment table that `occseg segment`, `occseg demo` and occseg_result_write
// write: {"dims": [nx, ny, nz], "voxel_size", "origin": [x, y, z], "preset": ..., "segments":
// [{"id", "state", "kind", "voxels", "mop", "bbox": {"min", "max"}, "centroid", "box_m": {"min",
// "max"}, "size_m", "centroid_m"}, ...]}, one segment a line; bbox and centroid in voxel indices,
// the *_m fields in metres in the map's frame (origin + voxel_size x index; the box from the min
// corner to the max corner of its voxels, the centroid as the mean voxel centre). With the
// oriented boxes (the overload taking a SegmentsFrame) also per segment "obb": {"center",
// "extents", "quaternion"} (metres; quaternion w, x, y, z; occseg/boxes.hpp) after "centroid_m".
#pragma once
#include <ostream>
#include <string>

#include <array>
#include <vector>

#include "occseg/boxes.hpp"
#include "occseg/segment.hpp"

namespace occseg {

// Streams the table to `out` segment by segment. It builds no document in memory, so a table of
// millions of segments needs no memory beyond the result (and out of memory cannot strike while a
// document is being torn down, where an exception would end the process). Numbers are printed
// in the shortest form that reads back as the same double.
void write_segments_json(std::ostream& out, const Result& r, const std::string& preset);

// The map's frame and the segments' oriented boxes (oriented_boxes(r, voxel_size, origin)).
struct SegmentsFrame {
  double voxel_size = 1;
  std::array<double, 3> origin{0, 0, 0};
  const std::vector<OrientedBox>* boxes = nullptr;  // one per segment, or null for none
};
void write_segments_json(std::ostream& out, const Result& r, const std::string& preset, const SegmentsFrame& frame);

}  // namespace occseg
