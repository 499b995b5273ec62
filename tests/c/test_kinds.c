/* The scene table's kinds through occseg_result_segment(), and old callers: a struct_size of the
 * layout before `kind` gets the old fields filled and nothing written beyond them. */
#include <stdlib.h>

#include "suite.h"

static occseg_result *kinds_result(void) {
  occseg_map *m = scene_map();
  occseg_result *r = NULL;
  assert_int_equal(occseg_segment(&r, m, NULL), OCCSEG_OK);
  occseg_map_free(m);
  return r;
}

static void kinds_follow_states(void **state) {
  occseg_result *r = kinds_result();
  uint32_t i;
  (void)state;
  assert_int_equal(occseg_result_segment_count(r), 3);
  for (i = 0; i < 3; ++i) {
    occseg_segment_info s;
    memset(&s, 0xAB, sizeof s);
    s.struct_size = sizeof s;
    assert_int_equal(occseg_result_segment(r, i, &s), OCCSEG_OK);
    /* The scene's two boxes (1000 and 4500 voxels) are objects, the rest free space. */
    if (s.state == OCCSEG_OCCUPIED) assert_int_equal(s.kind, OCCSEG_KIND_OBJECT);
    else assert_int_equal(s.kind, s.state == OCCSEG_FREE ? OCCSEG_KIND_FREE : OCCSEG_KIND_UNKNOWN);
  }
  occseg_result_free(r);
}

static void old_struct_size_fills_the_old_fields_only(void **state) {
  occseg_result *r = kinds_result();
  occseg_segment_info now, old;
  const unsigned char *bytes = (const unsigned char *)&old;
  size_t k;
  (void)state;
  assert_int_equal(OCCSEG_SEGMENT_INFO_SIZE_V1, offsetof(occseg_segment_info, kind));
  memset(&now, 0, sizeof now);
  now.struct_size = sizeof now;
  assert_int_equal(occseg_result_segment(r, 1, &now), OCCSEG_OK);
  memset(&old, 0xAB, sizeof old);
  old.struct_size = OCCSEG_SEGMENT_INFO_SIZE_V1;
  assert_int_equal(occseg_result_segment(r, 1, &old), OCCSEG_OK);
  assert_int_equal(old.id, now.id);
  assert_int_equal(old.state, now.state);
  assert_int_equal(old.voxels, now.voxels);
  assert_true(old.mop == now.mop);
  for (k = 0; k < 3; ++k) {
    assert_int_equal(old.bbox_min[k], now.bbox_min[k]);
    assert_int_equal(old.bbox_max[k], now.bbox_max[k]);
    assert_true(old.centroid[k] == now.centroid[k]);
  }
  for (k = OCCSEG_SEGMENT_INFO_SIZE_V1; k < sizeof old; ++k) assert_int_equal(bytes[k], 0xAB);
  occseg_result_free(r);
}

int run_kinds_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(kinds_follow_states),
      cmocka_unit_test(old_struct_size_fills_the_old_fields_only),
  };
  return cmocka_run_group_tests_name("kinds", tests, NULL, NULL);
}
