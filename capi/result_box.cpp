// occseg_result_segment_box: the oriented box of a segment in metres (occseg/boxes.hpp).
#include "internal.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::require;

extern "C" {

int occseg_result_segment_box(const occseg_result* result, uint32_t index, occseg_box* out) {
  return guard("occseg_result_segment_box", [&] {
    require(result, "result");
    require(out, "out");
    // One layout so far; a later version that appends fields will accept both sizes.
    if (out->struct_size != sizeof(occseg_box))
      throw Error(Status::invalid_argument, "out->struct_size " + std::to_string(out->struct_size) +
                                                " is not sizeof(occseg_box) = " + std::to_string(sizeof(occseg_box)));
    const auto& segs = result->result.segments;
    if (index >= segs.size())
      throw Error(Status::out_of_range, "index " + std::to_string(index) + " is out of range (the result has " +
                                            std::to_string(segs.size()) + " segments)");
    const occseg::OrientedBox& b = result->boxes()[index];
    for (int k = 0; k < 3; ++k) {
      out->center[k] = b.center[k];
      out->extents[k] = b.extents[k];
    }
    for (int k = 0; k < 4; ++k) out->quaternion[k] = b.quaternion[k];
  });
}

}  // extern "C"
