/* occseg_result_*: accessors, their error paths, stages and writing the result files. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "suite.h"

enum { SCENE_N = SCENE_NX * SCENE_NY * SCENE_NZ };

static occseg_result *scene_result(void) {
  occseg_map *m = scene_map();
  occseg_result *r = NULL;
  assert_int_equal(occseg_segment(&r, m, NULL), OCCSEG_OK);
  occseg_map_free(m); /* the result does not depend on the map */
  return r;
}

static void segment_info_errors(void **state) {
  occseg_result *r = scene_result();
  occseg_segment_info s;
  (void)state;
  memset(&s, 0, sizeof s);
  s.struct_size = sizeof s;
  EXPECT_FAIL(occseg_result_segment(r, 3, &s), OCCSEG_ERANGE, "index 3 is out of range (the result has 3 segments)");
  EXPECT_FAIL(occseg_result_segment(r, UINT32_MAX, &s), OCCSEG_ERANGE, "index 4294967295");
  EXPECT_FAIL(occseg_result_segment(r, 0, NULL), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_result_segment(NULL, 0, &s), OCCSEG_EINVAL, "'result'");
  s.struct_size = 0;
  EXPECT_FAIL(occseg_result_segment(r, 0, &s), OCCSEG_EINVAL, "out->struct_size 0 is not sizeof(occseg_segment_info)");
  s.struct_size = sizeof s - 4;
  EXPECT_FAIL(occseg_result_segment(r, 0, &s), OCCSEG_EINVAL, "struct_size");
  s.struct_size = OCCSEG_SEGMENT_INFO_SIZE_V1 - 8;
  EXPECT_FAIL(occseg_result_segment(r, 0, &s), OCCSEG_EINVAL, "struct_size");
  s.struct_size = sizeof s + 8;
  EXPECT_FAIL(occseg_result_segment(r, 0, &s), OCCSEG_EINVAL, "struct_size");
  assert_int_equal(s.voxels, 0); /* nothing written on failure */
  assert_int_equal(occseg_result_segment_count(NULL), 0);
  assert_non_null(strstr(occseg_last_error(), "'result'"));
  assert_int_equal(occseg_result_segment_count(r), 3);
  assert_string_equal(occseg_last_error(), "");
  occseg_result_free(r);
  occseg_result_free(NULL);
}

static void labels_and_states(void **state) {
  occseg_result *r = scene_result();
  uint32_t *labels = malloc((SCENE_N + 1) * sizeof *labels);
  uint8_t *states = malloc(SCENE_N + 1);
  size_t dims[3], i;
  (void)state;
  assert_true(labels && states);
  labels[SCENE_N] = 77;
  states[SCENE_N] = 77;
  EXPECT_FAIL(occseg_result_labels(r, labels, SCENE_N - 1), OCCSEG_ERANGE,
              "count 107519 is smaller than the 107520 voxels");
  EXPECT_FAIL(occseg_result_states(r, states, 0), OCCSEG_ERANGE, "count 0 is smaller");
  EXPECT_FAIL(occseg_result_labels(r, NULL, SCENE_N), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_result_labels(NULL, labels, SCENE_N), OCCSEG_EINVAL, "'result'");
  EXPECT_FAIL(occseg_result_states(r, NULL, SCENE_N), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_result_states(NULL, states, SCENE_N), OCCSEG_EINVAL, "'result'");
  EXPECT_FAIL(occseg_result_dims(NULL, dims), OCCSEG_EINVAL, "'result'");
  EXPECT_FAIL(occseg_result_dims(r, NULL), OCCSEG_EINVAL, "'dims'");
  /* A larger buffer is fine; only nx*ny*nz elements are written. */
  assert_int_equal(occseg_result_labels(r, labels, SCENE_N + 1), OCCSEG_OK);
  assert_int_equal(occseg_result_states(r, states, SCENE_N + 1), OCCSEG_OK);
  assert_int_equal(labels[SCENE_N], 77);
  assert_int_equal(states[SCENE_N], 77);
  for (i = 0; i < SCENE_N; ++i) assert_int_equal(states[i], labels[i] == 0 ? OCCSEG_FREE : OCCSEG_OCCUPIED);
  free(labels);
  free(states);
  occseg_result_free(r);
}

static void stages(void **state) {
  occseg_result *r = scene_result();
  static const char *const names[] = {"texture", "division", "creation", "refinement", "labelling"};
  const char *name = NULL;
  double seconds = -1;
  uint32_t i;
  (void)state;
  assert_int_equal(occseg_result_stage_count(r), 5);
  for (i = 0; i < 5; ++i) {
    assert_int_equal(occseg_result_stage(r, i, &name, &seconds), OCCSEG_OK);
    assert_string_equal(name, names[i]);
    assert_true(seconds >= 0.0);
  }
  assert_int_equal(occseg_result_stage(r, 0, NULL, NULL), OCCSEG_OK);
  EXPECT_FAIL(occseg_result_stage(r, 5, &name, &seconds), OCCSEG_ERANGE, "index 5 is out of range");
  EXPECT_FAIL(occseg_result_stage(NULL, 0, &name, &seconds), OCCSEG_EINVAL, "'result'");
  assert_int_equal(occseg_result_stage_count(NULL), 0);
  occseg_result_free(r);
}

static long file_size(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  long n = file_size(path);
  char *text = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (!f || !text) {
    if (f) fclose(f);
    free(text);
    return NULL;
  }
  text[fread(text, 1, (size_t)n, f)] = '\0';
  fclose(f);
  return text;
}

static void write_files(void **state) {
  occseg_result *r = scene_result();
  char *json;
  unsigned char head[10];
  FILE *f;
  (void)state;
  remove("c_suite_out/labels.npy");
  remove("c_suite_out/segments.json");
  assert_int_equal(occseg_result_write(r, "c_suite_out"), OCCSEG_OK);
  /* labels.npy: magic, version 1.0, a header padded to 64 bytes, 4 bytes per voxel. */
  f = fopen("c_suite_out/labels.npy", "rb");
  assert_non_null(f);
  assert_int_equal(fread(head, 1, 10, f), 10);
  fclose(f);
  assert_memory_equal(head, "\x93NUMPY\x01\x00", 8);
  assert_int_equal(file_size("c_suite_out/labels.npy"), 10 + (head[8] | head[9] << 8) + 4L * SCENE_N);
  assert_int_equal((10 + (head[8] | head[9] << 8)) % 64, 0);
  json = slurp("c_suite_out/segments.json");
  assert_non_null(json);
  assert_non_null(strstr(json, "\"dims\": [56, 48, 40]"));
  assert_non_null(strstr(json, "\"preset\": \"default\""));
  assert_non_null(strstr(json, "{\"id\": 1, \"state\": \"occupied\", \"kind\": \"object\", \"voxels\": 1000,"));
  assert_non_null(strstr(json, "\"bbox\": {\"min\": [30, 25, 20], \"max\": [49, 39, 34]}, \"centroid\": [39.5, 32, 27], \"box_m\": {\"min\": [3, 2.5, 2], \"max\": [5, 4, 3.5]}"));
  /* The map's frame and the segment's oriented box, in metres (voxels of 0.1 m). */
  assert_non_null(strstr(json, "\"voxel_size\": 0.1,\n \"origin\": [0, 0, 0]"));
  assert_non_null(strstr(json, "\"obb\": {\"center\": [4, 3.25, 2.75], \"extents\": [2, 1.5, 1.5], \"quaternion\": [1, 0, 0, 0]}}"));
  free(json);
  /* A directory whose parent is missing: an error naming it, and no file left behind. */
  EXPECT_FAIL(occseg_result_write(r, "c_suite_missing/out"), OCCSEG_EIO, "cannot create 'c_suite_missing/out'");
  assert_int_equal(file_size("c_suite_missing/out/labels.npy"), -1);
  EXPECT_FAIL(occseg_result_write(r, "c_suite_out/segments.json"), OCCSEG_EIO, "is not a directory");
  EXPECT_FAIL(occseg_result_write(NULL, "c_suite_out"), OCCSEG_EINVAL, "'result'");
  EXPECT_FAIL(occseg_result_write(r, NULL), OCCSEG_EINVAL, "'dir'");
  occseg_result_free(r);
}

int run_result_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(segment_info_errors),
      cmocka_unit_test(labels_and_states),
      cmocka_unit_test(stages),
      cmocka_unit_test(write_files),
  };
  return cmocka_run_group_tests_name("result", tests, NULL, NULL);
}
