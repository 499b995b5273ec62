/* The built-in readers take what the occseg command reads (issue 26): a big-endian .npy as NumPy
 * writes it, and a .nrrd read with voxel_size=, which replaces the file's spacing as the
 * command's --voxel-size does (the first voxel centre stays where it was); the import error of a
 * NaN or an out-of-range value names the one flag that accepts it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "suite.h"

/* A v1.0 .npy of one [1, 1, n] array, the header padded as numpy.save pads it. */
static void write_npy(const char *path, const char *descr, size_t n, const unsigned char *body, size_t bytes) {
  char dict[128];
  unsigned char pre[10] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0, 0, 0};
  size_t len;
  FILE *f;
  snprintf(dict, sizeof dict, "{'descr': '%s', 'fortran_order': False, 'shape': (1, 1, %u), }", descr, (unsigned)n);
  len = strlen(dict);
  while ((10 + len + 1) % 64) dict[len++] = ' ';
  dict[len++] = '\n';
  pre[8] = (unsigned char)len;
  f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(pre, 1, 10, f), 10);
  assert_int_equal(fwrite(dict, 1, len, f), len);
  assert_int_equal(fwrite(body, 1, bytes, f), bytes);
  assert_int_equal(fclose(f), 0);
}

static void big_endian_npy(void **state) {
  /* 0.5f, 1.0f and 0.25f most significant byte first; 0xffff and 0x0001 as >u2. */
  const unsigned char f4[12] = {0x3f, 0, 0, 0, 0x3f, 0x80, 0, 0, 0x3e, 0x80, 0, 0};
  const unsigned char u2[4] = {0xff, 0xff, 0x00, 0x01};
  occseg_map *m = NULL;
  float v[3];
  size_t dims[3];
  (void)state;
  write_npy("c_suite_be_f4.npy", ">f4", 3, f4, sizeof f4);
  assert_int_equal(occseg_map_read(&m, "c_suite_be_f4.npy"), OCCSEG_OK);
  assert_int_equal(occseg_map_dims(m, dims), OCCSEG_OK);
  assert_true(dims[0] == 3 && dims[1] == 1 && dims[2] == 1);
  assert_int_equal(occseg_map_values(m, v, 3), OCCSEG_OK);
  assert_true(v[0] == 0.5f && v[1] == 1.0f && v[2] == 0.25f);
  occseg_map_free(m);
  write_npy("c_suite_be_u2.npy", ">u2", 2, u2, sizeof u2);
  assert_int_equal(occseg_map_read(&m, "c_suite_be_u2.npy"), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, v, 2), OCCSEG_OK);
  assert_true(v[0] == 1.0f && v[1] == (float)(1 / 65535.0));
  occseg_map_free(m);
  write_npy("c_suite_be_c8.npy", ">c8", 1, f4, 8); /* complex: still refused, naming the dtype */
  EXPECT_FAIL(occseg_map_read(&m, "c_suite_be_c8.npy"), OCCSEG_EFORMAT, "dtype '>c8' is not supported");
  assert_null(m);
}

static void nrrd_voxel_size_option(void **state) {
  const float p[8] = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f};
  const size_t dims[3] = {2, 2, 2};
  const double origin[3] = {1.0, 2.0, 3.0};
  const char *opts[] = {"voxel_size=0.5", NULL}, *bad[] = {"voxel_size=-1", NULL}, *other[] = {"spacing=1", NULL};
  occseg_map *m = NULL, *r = NULL;
  double vs = 0, o[3];
  float v[8];
  (void)state;
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, dims, NULL, 0.25), OCCSEG_OK);
  assert_int_equal(occseg_map_set_origin(m, origin), OCCSEG_OK);
  assert_int_equal(occseg_map_write(m, "c_suite_vs.nrrd"), OCCSEG_OK);
  assert_int_equal(occseg_map_read_options(&r, "c_suite_vs.nrrd", opts), OCCSEG_OK);
  assert_int_equal(occseg_map_voxel_size(r, &vs), OCCSEG_OK);
  assert_true(vs == 0.5);
  /* The first voxel's centre, 1.125 etc., stays: the corner moves by (0.25 - 0.5) / 2. */
  assert_int_equal(occseg_map_origin(r, o), OCCSEG_OK);
  assert_true(o[0] == 1.0 - 0.125 && o[1] == 2.0 - 0.125 && o[2] == 3.0 - 0.125);
  assert_int_equal(occseg_map_values(r, v, 8), OCCSEG_OK);
  assert_memory_equal(v, p, sizeof p);
  occseg_map_free(r);
  r = NULL;
  EXPECT_FAIL(occseg_map_read_options(&r, "c_suite_vs.nrrd", bad), OCCSEG_EINVAL, "voxel_size must be a positive number");
  EXPECT_FAIL(occseg_map_read_options(&r, "c_suite_vs.nrrd", other), OCCSEG_EINVAL, "unknown option 'spacing=1' (known: voxel_size)");
  assert_null(r);
  occseg_map_free(m);
}

static void import_errors_name_the_flag_that_accepts_the_value(void **state) {
  const float nan_value[1] = {NAN}, big[1] = {1.5f};
  const size_t dims[3] = {1, 1, 1};
  occseg_map *m = NULL;
  (void)state;
  EXPECT_FAIL(occseg_map_from_buffer(&m, nan_value, OCCSEG_F32, dims, NULL, 1.0), OCCSEG_EVALUE,
              "is NaN (pass OCCSEG_IMPORT_NAN_UNKNOWN to read it as unknown)");
  EXPECT_FAIL(occseg_map_from_buffer(&m, big, OCCSEG_F32, dims, NULL, 1.0), OCCSEG_EVALUE,
              "is outside [0, 1] (pass OCCSEG_IMPORT_CLAMP to clamp it to [0, 1])");
  assert_null(m);
}

int run_reader_options_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(big_endian_npy),
      cmocka_unit_test(nrrd_voxel_size_option),
      cmocka_unit_test(import_errors_name_the_flag_that_accepts_the_value),
  };
  return cmocka_run_group_tests_name("reader_options", tests, NULL, NULL);
}
