/* occseg_params_*: typed and text setters and getters, presets, copies, validation. */
#include <math.h>

#include "suite.h"

static int64_t get_i(const occseg_params *p, const char *name) {
  int64_t v = -12345;
  assert_int_equal(occseg_params_get_int(p, name, &v), OCCSEG_OK);
  return v;
}

static double get_d(const occseg_params *p, const char *name) {
  double v = -12345;
  assert_int_equal(occseg_params_get_double(p, name, &v), OCCSEG_OK);
  return v;
}

static void defaults(void **state) {
  occseg_params *p = NULL;
  char buf[32];
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_non_null(p);
  /* The paper's values (libseg/include/occseg/params.hpp). */
  assert_int_equal(get_i(p, "smax"), 64);
  assert_int_equal(get_i(p, "smin"), 8);
  assert_int_equal(get_i(p, "contrast_bins"), 8);
  assert_true(get_d(p, "split_ratio") == 1.2);
  assert_true(get_d(p, "free_below") == 0.498);
  assert_true(get_d(p, "smax") == 64.0); /* _double reads int parameters too */
  assert_int_equal(occseg_params_get_string(p, "preset", buf, sizeof buf, NULL), OCCSEG_OK);
  assert_string_equal(buf, "default");
  assert_int_equal(occseg_params_get(p, "smax", buf, sizeof buf, NULL), OCCSEG_OK);
  assert_string_equal(buf, "64");
  assert_int_equal(occseg_params_validate(p), OCCSEG_OK);
  occseg_params_free(p);
  occseg_params_free(NULL);
}

static void typed_setters(void **state) {
  occseg_params *p = NULL;
  char buf[32];
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set_int(p, "smax", 32), OCCSEG_OK);
  assert_int_equal(get_i(p, "smax"), 32);
  EXPECT_FAIL(occseg_params_set_int(p, "smax", 5000), OCCSEG_EINVAL, "5000 is outside [2, 4096]");
  EXPECT_FAIL(occseg_params_set_int(p, "smax", INT64_MIN), OCCSEG_EINVAL, "parameter 'smax'");
  assert_int_equal(get_i(p, "smax"), 32); /* unchanged by the failures */
  assert_int_equal(occseg_params_set_int(p, "free_below", 0), OCCSEG_OK);
  assert_true(get_d(p, "free_below") == 0.0);
  EXPECT_FAIL(occseg_params_set_int(p, "preset", 1), OCCSEG_EINVAL, "use occseg_params_set_string");

  assert_int_equal(occseg_params_set_double(p, "split_ratio", 1.5), OCCSEG_OK);
  assert_true(get_d(p, "split_ratio") == 1.5);
  assert_int_equal(occseg_params_set_double(p, "occupied_above", 0.123456789012345678), OCCSEG_OK);
  assert_true(get_d(p, "occupied_above") == 0.123456789012345678); /* exact round trip */
  assert_int_equal(occseg_params_set_double(p, "smin", 16.0), OCCSEG_OK);
  assert_int_equal(get_i(p, "smin"), 16);
  EXPECT_FAIL(occseg_params_set_double(p, "smin", 16.5), OCCSEG_EINVAL, "is not an integer");
  EXPECT_FAIL(occseg_params_set_double(p, "split_ratio", NAN), OCCSEG_EINVAL, "is not a finite number");
  EXPECT_FAIL(occseg_params_set_double(p, "split_ratio", INFINITY), OCCSEG_EINVAL, "is not a finite number");
  EXPECT_FAIL(occseg_params_set_double(p, "free_below", 1.5), OCCSEG_EINVAL, "outside [0, 1]");
  EXPECT_FAIL(occseg_params_set_double(p, "preset", 1.0), OCCSEG_EINVAL, "use occseg_params_set_string");
  assert_true(get_d(p, "split_ratio") == 1.5);

  assert_int_equal(occseg_params_set_string(p, "preset", "paper"), OCCSEG_OK);
  assert_int_equal(occseg_params_get_string(p, "preset", buf, sizeof buf, NULL), OCCSEG_OK);
  assert_string_equal(buf, "paper");
  assert_int_equal(get_i(p, "smax"), 64); /* the preset reset everything */
  EXPECT_FAIL(occseg_params_set_string(p, "preset", "fast"), OCCSEG_EINVAL, "'fast' is not a preset");
  EXPECT_FAIL(occseg_params_set_string(p, "smax", "32"), OCCSEG_EINVAL, "is of kind int");
  EXPECT_FAIL(occseg_params_set_string(p, "preset", NULL), OCCSEG_EINVAL, "'value'");
  occseg_params_free(p);
}

static void text_setter_and_presets(void **state) {
  occseg_params *p = NULL;
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set(p, "smax", "16"), OCCSEG_OK);
  assert_int_equal(occseg_params_set(p, "split_ratio", "2.5"), OCCSEG_OK);
  assert_int_equal(get_i(p, "smax"), 16);
  assert_true(get_d(p, "split_ratio") == 2.5);
  EXPECT_FAIL(occseg_params_set(p, "smax", "sixteen"), OCCSEG_EINVAL, "'sixteen' is not a number");
  EXPECT_FAIL(occseg_params_set(p, "smax", ""), OCCSEG_EINVAL, "is not a number");
  EXPECT_FAIL(occseg_params_set(p, "speed", "1"), OCCSEG_EINVAL, "parameter 'speed': no such parameter");
  EXPECT_FAIL(occseg_params_set(NULL, "smax", "1"), OCCSEG_EINVAL, "argument 'params' is NULL");
  EXPECT_FAIL(occseg_params_set(p, NULL, "1"), OCCSEG_EINVAL, "argument 'name' is NULL");
  EXPECT_FAIL(occseg_params_set(p, "smax", NULL), OCCSEG_EINVAL, "argument 'value' is NULL");
  assert_int_equal(occseg_params_set(p, "preset", "default"), OCCSEG_OK);
  assert_int_equal(get_i(p, "smax"), 64);
  assert_int_equal(occseg_params_set_int(p, "smax", 16), OCCSEG_OK);
  assert_int_equal(occseg_params_preset(p, "paper"), OCCSEG_OK);
  assert_int_equal(get_i(p, "smax"), 64);
  EXPECT_FAIL(occseg_params_preset(p, "quick"), OCCSEG_EINVAL, "'quick' is not a preset");
  EXPECT_FAIL(occseg_params_preset(p, NULL), OCCSEG_EINVAL, "'name'");
  EXPECT_FAIL(occseg_params_preset(NULL, "paper"), OCCSEG_EINVAL, "'params'");
  occseg_params_free(p);
}

static void getters(void **state) {
  occseg_params *p = NULL;
  int64_t i = 7;
  double d = 7;
  char buf[8];
  size_t len = 0;
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  EXPECT_FAIL(occseg_params_get_int(p, "split_ratio", &i), OCCSEG_EINVAL, "use occseg_params_get_double");
  EXPECT_FAIL(occseg_params_get_int(p, "preset", &i), OCCSEG_EINVAL, "use occseg_params_get_string");
  EXPECT_FAIL(occseg_params_get_int(p, "nope", &i), OCCSEG_EINVAL, "no such parameter");
  EXPECT_FAIL(occseg_params_get_int(p, "smax", NULL), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_params_get_int(NULL, "smax", &i), OCCSEG_EINVAL, "'params'");
  assert_int_equal(i, 7);
  EXPECT_FAIL(occseg_params_get_double(p, "preset", &d), OCCSEG_EINVAL, "use occseg_params_get_string");
  EXPECT_FAIL(occseg_params_get_double(p, NULL, &d), OCCSEG_EINVAL, "'name'");
  EXPECT_FAIL(occseg_params_get_double(p, "smax", NULL), OCCSEG_EINVAL, "'out'");
  assert_true(d == 7);
  EXPECT_FAIL(occseg_params_get_string(p, "smax", buf, sizeof buf, NULL), OCCSEG_EINVAL, "is of kind int");

  /* Length query, exact fit, one byte short (buffer untouched). */
  assert_int_equal(occseg_params_get(p, "preset", NULL, 0, &len), OCCSEG_OK);
  assert_int_equal(len, 7); /* "default" */
  memset(buf, 'x', sizeof buf);
  EXPECT_FAIL(occseg_params_get(p, "preset", buf, 7, &len), OCCSEG_ERANGE, "buffer of 7 bytes is too small");
  assert_int_equal(len, 7);
  assert_memory_equal(buf, "xxxxxxxx", 8);
  EXPECT_FAIL(occseg_params_get_string(p, "preset", buf, 3, NULL), OCCSEG_ERANGE, "needs 8");
  assert_int_equal(occseg_params_get(p, "preset", buf, 8, NULL), OCCSEG_OK);
  assert_string_equal(buf, "default");
  EXPECT_FAIL(occseg_params_get(p, "preset", NULL, 0, NULL), OCCSEG_EINVAL, "'length'");
  EXPECT_FAIL(occseg_params_get(p, "preset", NULL, 8, &len), OCCSEG_EINVAL, "'buf'");
  EXPECT_FAIL(occseg_params_get(p, "nope", buf, 8, &len), OCCSEG_EINVAL, "no such parameter");
  EXPECT_FAIL(occseg_params_get(NULL, "smax", buf, 8, &len), OCCSEG_EINVAL, "'params'");
  occseg_params_free(p);
}

static void copy_and_validate(void **state) {
  occseg_params *p = NULL, *q = (occseg_params *)&q;
  (void)state;
  EXPECT_FAIL(occseg_params_create(NULL), OCCSEG_EINVAL, "'out'");
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set_int(p, "smax", 32), OCCSEG_OK);
  assert_int_equal(occseg_params_copy(&q, p), OCCSEG_OK);
  assert_int_equal(get_i(q, "smax"), 32);
  assert_int_equal(occseg_params_set_int(q, "smax", 128), OCCSEG_OK);
  assert_int_equal(get_i(p, "smax"), 32); /* independent */
  occseg_params_free(q);
  q = (occseg_params *)&q;
  EXPECT_FAIL(occseg_params_copy(&q, NULL), OCCSEG_EINVAL, "'src'");
  assert_null(q); /* outputs are NULL after a failure */
  EXPECT_FAIL(occseg_params_copy(NULL, p), OCCSEG_EINVAL, "'out'");

  /* Combinations the single setters cannot see. */
  assert_int_equal(occseg_params_set_int(p, "smin", 64), OCCSEG_OK);
  EXPECT_FAIL(occseg_params_validate(p), OCCSEG_EINVAL, "smin': 64 is larger than smax = 32");
  assert_int_equal(occseg_params_set_int(p, "smin", 8), OCCSEG_OK);
  assert_int_equal(occseg_params_set_int(p, "smax", 48), OCCSEG_OK);
  EXPECT_FAIL(occseg_params_validate(p), OCCSEG_EINVAL, "48 is not a power of two");
  assert_int_equal(occseg_params_set_int(p, "smax", 64), OCCSEG_OK);
  assert_int_equal(occseg_params_set_double(p, "free_below", 0.6), OCCSEG_OK);
  assert_int_equal(occseg_params_set_double(p, "occupied_above", 0.4), OCCSEG_OK);
  EXPECT_FAIL(occseg_params_validate(p), OCCSEG_EINVAL, "free_below");
  EXPECT_FAIL(occseg_params_validate(NULL), OCCSEG_EINVAL, "'params'");
  EXPECT_FAIL(occseg_params_set_progress(NULL, NULL, NULL), OCCSEG_EINVAL, "'params'");
  occseg_params_free(p);
}

int run_params_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(defaults), cmocka_unit_test(typed_setters), cmocka_unit_test(text_setter_and_presets),
      cmocka_unit_test(getters),  cmocka_unit_test(copy_and_validate),
  };
  return cmocka_run_group_tests_name("params", tests, NULL, NULL);
}
