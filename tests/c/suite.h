/* Shared helpers of the CMocka suite of the C ABI (compiled against the installed occseg.h). */
#ifndef OCCSEG_TEST_SUITE_H
#define OCCSEG_TEST_SUITE_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include <occseg/occseg.h>

/* Asserts that `rc` is `code` and that occseg_last_error() mentions `needle`. */
#define EXPECT_FAIL(rc, code, needle) expect_fail((rc), (code), (needle), __FILE__, __LINE__)
void expect_fail(int rc, int code, const char *needle, const char *file, int line);

/* The scene of tests/cli/check_segment.py: 56 x 48 x 40 voxels of free space (p = 0.12) holding
 * two occupied boxes (p = 0.97): x, y, z in [5, 15)^3 and x in [30, 50), y in [25, 40),
 * z in [20, 35). Dense float32, x fastest; the caller frees it. */
enum { SCENE_NX = 56, SCENE_NY = 48, SCENE_NZ = 40 };
float *scene_values(void);
/* The scene as a map (voxel size 0.1). */
occseg_map *scene_map(void);

int run_basics_tests(void);
int run_params_tests(void);
int run_map_tests(void);
int run_strides_tests(void);
int run_segment_tests(void);
int run_result_tests(void);
int run_context_tests(void);
int run_reader_options_tests(void);
int run_boxes_tests(void);
int run_borrow_tests(void);
int run_kinds_tests(void);

#endif
