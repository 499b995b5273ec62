/* See c_calls.c. */
#ifndef OCCSEG_TEST_C_CALLS_H
#define OCCSEG_TEST_C_CALLS_H
#include "occseg/occseg.h"
#ifdef __cplusplus
extern "C" {
#endif
/* occseg_map_from_buffer_flags with the dtype as a plain int. */
int occseg_test_from_buffer(occseg_map **out, const void *data, int dtype, const size_t dims[3],
                            const ptrdiff_t strides[3], double voxel_size, uint32_t flags);
/* occseg_map_view_buffer with the dtype as a plain int. */
int occseg_test_view_buffer(occseg_map **out, const void *data, int dtype, const size_t dims[3],
                            const ptrdiff_t strides[3], double voxel_size, uint32_t flags);
/* occseg_stage_count and occseg_stage_name with the kind as a plain int. */
uint32_t occseg_test_stage_count(int kind);
const char *occseg_test_stage_name(int kind, uint32_t index);
#ifdef __cplusplus
}
#endif
#endif
