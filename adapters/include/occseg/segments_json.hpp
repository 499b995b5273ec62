// segments.json, the segment table that `occseg segment`, `occseg demo` and occseg_result_write
// write: {"dims": [nx, ny, nz], "preset": ..., "segments": [{"id", "state", "voxels", "mop",
// "bbox": {"min", "max"}, "centroid"}, ...]}, one segment a line.
#pragma once
#include <ostream>
#include <string>

#include "occseg/segment.hpp"

namespace occseg {

// Streams the table to `out` segment by segment. It builds no document in memory, so a table of
// millions of segments needs no memory beyond the result (and out of memory cannot strike while a
// document is being torn down, where an exception would end the process). Numbers are printed
// in the shortest form that reads back as the same double.
void write_segments_json(std::ostream& out, const Result& r, const std::string& preset);

}  // namespace occseg
