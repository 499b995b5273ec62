/* Version, status codes, the per-thread last error and the parameter table. */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>

#include "suite.h"

static void version_matches_project(void **state) {
  (void)state;
  /* CMakeLists.txt: project(occseg VERSION 0.1.0). */
  assert_int_equal(OCCSEG_VERSION_MAJOR, 0);
  assert_int_equal(OCCSEG_VERSION_MINOR, 1);
  assert_int_equal(OCCSEG_VERSION_PATCH, 0);
  assert_int_equal(OCCSEG_VERSION_NUMBER, 100);
  assert_int_equal(occseg_version_number(), 100);
  assert_string_equal(OCCSEG_VERSION_STRING, "0.1.0");
  assert_string_equal(occseg_version_string(), "0.1.0");
}

static void status_codes_are_pinned(void **state) {
  static const struct {
    int code;
    int value;
    const char *name;
  } pinned[] = {{OCCSEG_OK, 0, "OCCSEG_OK"},
                {OCCSEG_EINVAL, -1, "OCCSEG_EINVAL"},
                {OCCSEG_EDIMS, -2, "OCCSEG_EDIMS"},
                {OCCSEG_EVALUE, -3, "OCCSEG_EVALUE"},
                {OCCSEG_ENOMEM, -4, "OCCSEG_ENOMEM"},
                {OCCSEG_EIO, -5, "OCCSEG_EIO"},
                {OCCSEG_EFORMAT, -6, "OCCSEG_EFORMAT"},
                {OCCSEG_ERANGE, -7, "OCCSEG_ERANGE"},
                {OCCSEG_ECANCELLED, -8, "OCCSEG_ECANCELLED"},
                {OCCSEG_EPLUGIN, -9, "OCCSEG_EPLUGIN"},
                {OCCSEG_EUNSUPPORTED, -10, "OCCSEG_EUNSUPPORTED"},
                {OCCSEG_EINTERNAL, -11, "OCCSEG_EINTERNAL"}};
  size_t i;
  (void)state;
  for (i = 0; i < sizeof pinned / sizeof pinned[0]; ++i) {
    assert_int_equal(pinned[i].code, pinned[i].value);
    assert_string_equal(occseg_status_name(pinned[i].value), pinned[i].name);
    assert_true(strlen(occseg_status_string(pinned[i].value)) > 0);
    assert_string_not_equal(occseg_status_string(pinned[i].value), "unknown status");
  }
  assert_string_equal(occseg_status_string(OCCSEG_EINVAL), "invalid argument");
  assert_string_equal(occseg_status_string(OCCSEG_ENOMEM), "out of memory");
  assert_string_equal(occseg_status_string(OCCSEG_ECANCELLED), "cancelled");
  assert_string_equal(occseg_status_name(-12), "OCCSEG_E?");
  assert_string_equal(occseg_status_name(1), "OCCSEG_E?");
  assert_string_equal(occseg_status_string(-12), "unknown status");
}

static void last_error_is_set_and_cleared(void **state) {
  occseg_params *p = NULL;
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_string_equal(occseg_last_error(), "");
  EXPECT_FAIL(occseg_params_set(p, "smax", "abc"), OCCSEG_EINVAL, "occseg_params_set: parameter 'smax'");
  assert_non_null(strstr(occseg_last_error(), "'abc' is not a number"));
  assert_int_equal(occseg_params_set(p, "smax", "32"), OCCSEG_OK);
  assert_string_equal(occseg_last_error(), "");
  occseg_params_free(p);
}

static void *fail_in_thread(void *arg) {
  char *seen = arg;
  occseg_params *p = NULL;
  if (occseg_params_create(&p) != OCCSEG_OK) return NULL;
  /* This thread starts clean although the main thread's last call failed. */
  seen[0] = occseg_last_error()[0] == '\0' ? 'c' : 'd';
  if (occseg_params_set(p, "bogus_thread", "1") == OCCSEG_EINVAL && strstr(occseg_last_error(), "bogus_thread"))
    seen[1] = 'f';
  occseg_params_free(p);
  return NULL;
}

static void last_error_is_per_thread(void **state) {
  occseg_params *p = NULL;
  pthread_t t;
  char seen[3] = "--";
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  EXPECT_FAIL(occseg_params_set(p, "bogus_main", "1"), OCCSEG_EINVAL, "bogus_main");
  assert_int_equal(pthread_create(&t, NULL, fail_in_thread, seen), 0);
  assert_int_equal(pthread_join(t, NULL), 0);
  assert_string_equal(seen, "cf");
  /* The other thread's failure did not overwrite this thread's text. */
  assert_non_null(strstr(occseg_last_error(), "bogus_main"));
  occseg_params_free(p);
}

static void param_table(void **state) {
  uint32_t n = occseg_param_count(), i, idx = 99;
  double lo = -1, hi = -1;
  static const char *const names[] = {"preset", "smax", "smin", "split_ratio", "contrast_bins", "free_below",
                                      "occupied_above", "lookahead", "refine_passes", "gap_radius", "occupied_connectivity", "support_plane",
                                      "object_gap", "min_object_voxels", "min_pocket_voxels", "surface_band",
                                      "structure_planes", "structure_extent", "plane_holes", "threads",
                                      "texture", "similarity"};
  (void)state;
  assert_int_equal(n, 22); /* built-in parameters only: this suite loads no plugin */
  for (i = 0; i < n; ++i) {
    assert_string_equal(occseg_param_name(i), names[i]);
    assert_true(strlen(occseg_param_description(i)) > 10);
    assert_int_equal(occseg_param_find(names[i], &idx), OCCSEG_OK);
    assert_int_equal(idx, i);
  }
  assert_string_equal(occseg_param_kind(0), "string");
  assert_string_equal(occseg_param_kind(1), "int");
  assert_string_equal(occseg_param_kind(3), "double");
  assert_int_equal(occseg_param_bounds(1, &lo, &hi), OCCSEG_OK);
  assert_true(lo == 2 && hi == 4096);
  assert_int_equal(occseg_param_bounds(0, &lo, &hi), OCCSEG_OK);
  assert_true(lo == 0 && hi == 0);
  assert_int_equal(occseg_param_bounds(5, &lo, &hi), OCCSEG_OK); /* free_below */
  assert_true(lo == 0 && hi == 1);
  /* Past the end and bad arguments. */
  assert_null(occseg_param_name(n));
  assert_null(occseg_param_kind(n));
  assert_null(occseg_param_description(UINT32_MAX));
  EXPECT_FAIL(occseg_param_bounds(n, &lo, &hi), OCCSEG_ERANGE, "index 22 is out of range");
  EXPECT_FAIL(occseg_param_bounds(0, NULL, &hi), OCCSEG_EINVAL, "'min'");
  EXPECT_FAIL(occseg_param_bounds(0, &lo, NULL), OCCSEG_EINVAL, "'max'");
  EXPECT_FAIL(occseg_param_find("nope", &idx), OCCSEG_EINVAL, "parameter 'nope': no such parameter");
  EXPECT_FAIL(occseg_param_find(NULL, &idx), OCCSEG_EINVAL, "'name'");
  EXPECT_FAIL(occseg_param_find("smax", NULL), OCCSEG_EINVAL, "'index'");
}

int run_basics_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(version_matches_project), cmocka_unit_test(status_codes_are_pinned),
      cmocka_unit_test(last_error_is_set_and_cleared), cmocka_unit_test(last_error_is_per_thread),
      cmocka_unit_test(param_table),
  };
  return cmocka_run_group_tests_name("basics", tests, NULL, NULL);
}
