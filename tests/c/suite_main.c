/* The CMocka suite of the C ABI: every function, every error path. */
#include <stdio.h>
#include <stdlib.h>

#include "suite.h"

void expect_fail(int rc, int code, const char *needle, const char *file, int line) {
  const char *msg = occseg_last_error();
  if (rc != code)
    fail_msg("%s:%d: status %d (%s), expected %d (%s); last error: %s", file, line, rc, occseg_status_name(rc),
             code, occseg_status_name(code), msg);
  if (!strstr(msg, needle))
    fail_msg("%s:%d: last error \"%s\" does not mention \"%s\"", file, line, msg, needle);
}

float *scene_values(void) {
  const size_t n = (size_t)SCENE_NX * SCENE_NY * SCENE_NZ;
  float *p = malloc(n * sizeof *p);
  size_t x, y, z;
  if (!p) return NULL;
  for (z = 0; z < SCENE_NZ; ++z)
    for (y = 0; y < SCENE_NY; ++y)
      for (x = 0; x < SCENE_NX; ++x) {
        const int box1 = x >= 5 && x < 15 && y >= 5 && y < 15 && z >= 5 && z < 15;
        const int box2 = x >= 30 && x < 50 && y >= 25 && y < 40 && z >= 20 && z < 35;
        p[x + SCENE_NX * (y + SCENE_NY * z)] = box1 || box2 ? 0.97f : 0.12f;
      }
  return p;
}

occseg_map *scene_map(void) {
  const size_t dims[3] = {SCENE_NX, SCENE_NY, SCENE_NZ};
  float *p = scene_values();
  occseg_map *map = NULL;
  assert_non_null(p);
  assert_int_equal(occseg_map_from_buffer(&map, p, OCCSEG_F32, dims, NULL, 0.1), OCCSEG_OK);
  free(p);
  return map;
}

int main(void) {
  int failed = 0;
  failed += run_basics_tests();
  failed += run_params_tests();
  failed += run_map_tests();
  failed += run_strides_tests();
  failed += run_segment_tests();
  failed += run_result_tests();
  failed += run_context_tests();
  failed += run_reader_options_tests();
  failed += run_boxes_tests();
  failed += run_borrow_tests();
  failed += run_kinds_tests();
  printf("occseg C suite: %d failed\n", failed);
  return failed == 0 ? 0 : 1;
}
