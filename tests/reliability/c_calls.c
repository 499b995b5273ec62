/* Calls that pass enum arguments outside their enumerators, as C callers may: in C an enum
 * is an int, while in C++ forming such a value is undefined behaviour (which UBSan reports). */
#include "c_calls.h"

int occseg_test_from_buffer(occseg_map **out, const void *data, int dtype, const size_t dims[3],
                            const ptrdiff_t strides[3], double voxel_size, uint32_t flags) {
  return occseg_map_from_buffer_flags(out, data, (occseg_dtype)dtype, dims, strides, voxel_size, flags);
}

int occseg_test_view_buffer(occseg_map **out, const void *data, int dtype, const size_t dims[3],
                            const ptrdiff_t strides[3], double voxel_size, uint32_t flags) {
  return occseg_map_view_buffer(out, data, (occseg_dtype)dtype, dims, strides, voxel_size, flags);
}

uint32_t occseg_test_stage_count(int kind) { return occseg_stage_count((occseg_stage_kind)kind); }

const char *occseg_test_stage_name(int kind, uint32_t index) { return occseg_stage_name((occseg_stage_kind)kind, index); }
