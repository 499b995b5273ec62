/* occseg_result_segment_box: oriented boxes in metres on the suite's scene, and the error paths;
 * occseg_result_write_outputs: the command's files by name. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "suite.h"

/* The scene with its origin moved to (1, 2, 3) m: boxes are in the map's world frame. */
static occseg_result *moved_scene_result(void) {
  const double origin[3] = {1.0, 2.0, 3.0};
  occseg_map *m = scene_map();
  occseg_result *r = NULL;
  assert_int_equal(occseg_map_set_origin(m, origin), OCCSEG_OK);
  assert_int_equal(occseg_segment(&r, m, NULL), OCCSEG_OK);
  occseg_map_free(m);
  return r;
}

static void expect_box(const occseg_box *b, const double c[3], const double e[3]) {
  int k;
  for (k = 0; k < 3; ++k) {
    if (fabs(b->center[k] - c[k]) > 1e-9) fail_msg("center[%d] = %.17g, expected %.17g", k, b->center[k], c[k]);
    if (fabs(b->extents[k] - e[k]) > 1e-9) fail_msg("extents[%d] = %.17g, expected %.17g", k, b->extents[k], e[k]);
  }
  /* Axis-aligned boxes: exactly the identity rotation. */
  assert_true(b->quaternion[0] == 1.0 && b->quaternion[1] == 0.0 && b->quaternion[2] == 0.0 && b->quaternion[3] == 0.0);
}

static void boxes_of_the_scene(void **state) {
  occseg_result *r = moved_scene_result();
  uint32_t i, n = occseg_result_segment_count(r), objects = 0;
  (void)state;
  for (i = 0; i < n; ++i) {
    occseg_segment_info s;
    occseg_box b;
    s.struct_size = sizeof s;
    b.struct_size = sizeof b;
    assert_int_equal(occseg_result_segment(r, i, &s), OCCSEG_OK);
    assert_int_equal(occseg_result_segment_box(r, i, &b), OCCSEG_OK);
    assert_string_equal(occseg_last_error(), "");
    if (s.state != OCCSEG_OCCUPIED) {
      /* Free space: the whole 5.6 x 4.8 x 4 m map. */
      const double c[3] = {1.0 + 2.8, 2.0 + 2.4, 3.0 + 2.0}, e[3] = {5.6, 4.8, 4.0};
      expect_box(&b, c, e);
    } else if (s.bbox_min[0] == 5) { /* voxels [5, 15)^3 of 0.1 m */
      const double c[3] = {2.0, 3.0, 4.0}, e[3] = {1.0, 1.0, 1.0};
      expect_box(&b, c, e);
      ++objects;
    } else { /* x in [30, 50), y in [25, 40), z in [20, 35) */
      const double c[3] = {1.0 + 4.0, 2.0 + 3.25, 3.0 + 2.75}, e[3] = {2.0, 1.5, 1.5};
      expect_box(&b, c, e);
      ++objects;
    }
  }
  assert_int_equal(objects, 2);
  occseg_result_free(r);
}

static void box_errors(void **state) {
  occseg_result *r = moved_scene_result();
  occseg_box b;
  (void)state;
  memset(&b, 0, sizeof b);
  b.struct_size = sizeof b;
  EXPECT_FAIL(occseg_result_segment_box(r, 3, &b), OCCSEG_ERANGE, "index 3 is out of range (the result has 3 segments)");
  EXPECT_FAIL(occseg_result_segment_box(r, UINT32_MAX, &b), OCCSEG_ERANGE, "index 4294967295");
  EXPECT_FAIL(occseg_result_segment_box(r, 0, NULL), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_result_segment_box(NULL, 0, &b), OCCSEG_EINVAL, "'result'");
  b.struct_size = 0;
  EXPECT_FAIL(occseg_result_segment_box(r, 0, &b), OCCSEG_EINVAL, "out->struct_size 0 is not sizeof(occseg_box)");
  b.struct_size = sizeof b + 8;
  EXPECT_FAIL(occseg_result_segment_box(r, 0, &b), OCCSEG_EINVAL, "struct_size");
  assert_true(b.extents[0] == 0.0); /* nothing written on failure */
  occseg_result_free(r);
}

static int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

static void write_outputs_by_name(void **state) {
  occseg_result *r = moved_scene_result();
  const char *all[] = {"labels.npy", "labels.nrrd", "segments.json", "segments.ply", NULL};
  const char *png[] = {"segments.json", "segmentation.png", NULL};
  const char *bogus[] = {"labels.nrrd", "passwords.txt", NULL};
  const char *twice[] = {"labels.nrrd", "labels.nrrd", NULL};
  const char *flat[] = {"segmentation.pgm", NULL};
  FILE *f;
  char head[64] = {0};
  (void)state;
  (void)!system("rm -rf c_outputs");
  /* Refused before anything is written: no directory is created. */
  EXPECT_FAIL(occseg_result_write_outputs(r, "c_outputs", png), OCCSEG_EUNSUPPORTED,
              "'segmentation.png' is written by the occseg command only");
  EXPECT_FAIL(occseg_result_write_outputs(r, "c_outputs", bogus), OCCSEG_EINVAL, "'passwords.txt' is not an output file");
  EXPECT_FAIL(occseg_result_write_outputs(r, "c_outputs", twice), OCCSEG_EINVAL, "'labels.nrrd' is named twice");
  EXPECT_FAIL(occseg_result_write_outputs(r, "c_outputs", flat), OCCSEG_EINVAL, "2D maps (nz = 1) only");
  EXPECT_FAIL(occseg_result_write_outputs(NULL, "c_outputs", NULL), OCCSEG_EINVAL, "'result'");
  EXPECT_FAIL(occseg_result_write_outputs(r, NULL, NULL), OCCSEG_EINVAL, "'dir'");
  assert_false(exists("c_outputs"));
  /* The default set of a 3D map. */
  assert_int_equal(occseg_result_write_outputs(r, "c_outputs", NULL), OCCSEG_OK);
  assert_true(exists("c_outputs/labels.nrrd") && exists("c_outputs/segments.json"));
  assert_false(exists("c_outputs/labels.npy") || exists("c_outputs/segmentation.pgm"));
  /* By name: PLY and the NRRD with the map's origin (1, 2, 3) m. */
  assert_int_equal(occseg_result_write_outputs(r, "c_outputs", all), OCCSEG_OK);
  assert_true(exists("c_outputs/labels.npy") && exists("c_outputs/segments.ply"));
  f = fopen("c_outputs/segments.ply", "rb");
  assert_non_null(f);
  assert_int_equal(fread(head, 1, 35, f), 35);
  fclose(f);
  assert_string_equal(head, "ply\nformat binary_little_endian 1.0");
  occseg_result_free(r);
}

int run_boxes_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(boxes_of_the_scene),
      cmocka_unit_test(box_errors),
      cmocka_unit_test(write_outputs_by_name),
  };
  return cmocka_run_group_tests_name("boxes", tests, NULL, NULL);
}
