/* occseg_map_*: dtypes, value checks, accessors, .npy and .nrrd files, argument errors. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "suite.h"

static const size_t k444[3] = {4, 4, 4};

static void dtypes_map_onto_probabilities(void **state) {
  const uint8_t u8[4] = {0, 255, 51, 128};
  const uint16_t u16[4] = {0, 65535, 13107, 32768};
  const double f64[4] = {0.0, 1.0, 0.25, 0.5};
  const float f32[4] = {0.0f, 1.0f, 0.75f, 1e-30f};
  const size_t dims[3] = {2, 2, 1};
  float out[4];
  occseg_map *m = NULL;
  (void)state;
  assert_int_equal(occseg_map_from_buffer(&m, u8, OCCSEG_U8, dims, NULL, 1.0), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 4), OCCSEG_OK);
  assert_true(out[0] == 0.0f && out[1] == 1.0f && out[2] == (float)(51 / 255.0) && out[3] == (float)(128 / 255.0));
  assert_true(fabsf(out[2] - 0.2f) < 1e-7f);
  occseg_map_free(m);
  assert_int_equal(occseg_map_from_buffer(&m, u16, OCCSEG_U16, dims, NULL, 1.0), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 4), OCCSEG_OK);
  assert_true(out[0] == 0.0f && out[1] == 1.0f && out[2] == (float)(13107 / 65535.0));
  assert_true(fabsf(out[2] - 0.2f) < 1e-7f && fabsf(out[3] - 0.5f) < 1e-4f);
  occseg_map_free(m);
  assert_int_equal(occseg_map_from_buffer(&m, f64, OCCSEG_F64, dims, NULL, 1.0), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 4), OCCSEG_OK);
  assert_true(out[0] == 0.0f && out[1] == 1.0f && out[2] == 0.25f && out[3] == 0.5f);
  occseg_map_free(m);
  assert_int_equal(occseg_map_from_buffer(&m, f32, OCCSEG_F32, dims, NULL, 1.0), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 4), OCCSEG_OK);
  assert_memory_equal(out, f32, sizeof f32);
  occseg_map_free(m);
}

static void accessors(void **state) {
  occseg_map *m = NULL;
  float p[64] = {0};
  size_t dims[3] = {0, 0, 0};
  double vs = 0, origin[3] = {1, 1, 1};
  const double o2[3] = {-1.5, 2.25, 1e3}, bad[3] = {0, NAN, 0};
  (void)state;
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, (const size_t[3]){4, 8, 2}, NULL, 0.05), OCCSEG_OK);
  assert_int_equal(occseg_map_dims(m, dims), OCCSEG_OK);
  assert_true(dims[0] == 4 && dims[1] == 8 && dims[2] == 2);
  assert_int_equal(occseg_map_voxel_size(m, &vs), OCCSEG_OK);
  assert_true(vs == 0.05);
  assert_int_equal(occseg_map_origin(m, origin), OCCSEG_OK);
  assert_true(origin[0] == 0 && origin[1] == 0 && origin[2] == 0);
  assert_int_equal(occseg_map_set_origin(m, o2), OCCSEG_OK);
  assert_int_equal(occseg_map_origin(m, origin), OCCSEG_OK);
  assert_memory_equal(origin, o2, sizeof o2);
  EXPECT_FAIL(occseg_map_set_origin(m, bad), OCCSEG_EVALUE, "origin[1] = nan is not finite");
  EXPECT_FAIL(occseg_map_set_origin(m, NULL), OCCSEG_EINVAL, "'origin'");
  EXPECT_FAIL(occseg_map_set_origin(NULL, o2), OCCSEG_EINVAL, "'map'");
  assert_int_equal(occseg_map_origin(m, origin), OCCSEG_OK);
  assert_memory_equal(origin, o2, sizeof o2); /* unchanged by the failure */
  assert_int_equal(occseg_map_set_voxel_size(m, 0.2), OCCSEG_OK);
  assert_int_equal(occseg_map_voxel_size(m, &vs), OCCSEG_OK);
  assert_true(vs == 0.2);
  EXPECT_FAIL(occseg_map_set_voxel_size(m, 0.0), OCCSEG_EVALUE, "voxel_size 0 is not a positive finite number");
  EXPECT_FAIL(occseg_map_set_voxel_size(m, -1.0), OCCSEG_EVALUE, "voxel_size -1");
  EXPECT_FAIL(occseg_map_set_voxel_size(m, INFINITY), OCCSEG_EVALUE, "voxel_size inf");
  EXPECT_FAIL(occseg_map_set_voxel_size(NULL, 1.0), OCCSEG_EINVAL, "'map'");
  EXPECT_FAIL(occseg_map_dims(NULL, dims), OCCSEG_EINVAL, "'map'");
  EXPECT_FAIL(occseg_map_dims(m, NULL), OCCSEG_EINVAL, "'dims'");
  EXPECT_FAIL(occseg_map_voxel_size(NULL, &vs), OCCSEG_EINVAL, "'map'");
  EXPECT_FAIL(occseg_map_voxel_size(m, NULL), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_map_origin(NULL, origin), OCCSEG_EINVAL, "'map'");
  EXPECT_FAIL(occseg_map_origin(m, NULL), OCCSEG_EINVAL, "'origin'");
  EXPECT_FAIL(occseg_map_values(m, p, 63), OCCSEG_ERANGE, "count 63 is smaller than the 64 voxels");
  EXPECT_FAIL(occseg_map_values(m, NULL, 64), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_map_values(NULL, p, 64), OCCSEG_EINVAL, "'map'");
  occseg_map_free(m);
  occseg_map_free(NULL);
}

static void argument_errors(void **state) {
  float p[64] = {0};
  occseg_map *m = (occseg_map *)&m;
  const size_t zero[3] = {4, 0, 4}, huge[3] = {SIZE_MAX, 2, 2}, big[3] = {(size_t)1 << 21, (size_t)1 << 21, 1};
  (void)state;
  EXPECT_FAIL(occseg_map_from_buffer(NULL, p, OCCSEG_F32, k444, NULL, 1.0), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_map_from_buffer(&m, NULL, OCCSEG_F32, k444, NULL, 1.0), OCCSEG_EINVAL, "argument 'data' is NULL");
  assert_null(m);
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, NULL, NULL, 1.0), OCCSEG_EINVAL, "'dims'");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, (occseg_dtype)7, k444, NULL, 1.0), OCCSEG_EINVAL,
              "dtype 7 is not an occseg_dtype");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, (occseg_dtype)5, k444, NULL, 1.0), OCCSEG_EINVAL,
              "dtype 5 is not an occseg_dtype (OCCSEG_F32 .. OCCSEG_I8_OCCUPANCY)");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, (occseg_dtype)-1, k444, NULL, 1.0), OCCSEG_EINVAL, "dtype -1");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, zero, NULL, 1.0), OCCSEG_EDIMS, "4 x 0 x 4 have a zero");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, huge, NULL, 1.0), OCCSEG_EDIMS, "exceed the limit of 2^40");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, big, NULL, 1.0), OCCSEG_EDIMS, "2097152 x 2097152 x 1");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, NULL, 0.0), OCCSEG_EVALUE, "voxel_size 0");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, NULL, NAN), OCCSEG_EVALUE, "voxel_size nan");
  EXPECT_FAIL(occseg_map_from_buffer_flags(&m, p, OCCSEG_F32, k444, NULL, 1.0, 8), OCCSEG_EINVAL, "flags 8");
  assert_null(m);
}

static void out_of_memory_is_reported(void **state) {
  /* 2^40 voxels pass the dimension check but cannot be allocated (4 TiB of floats); the
   * allocation fails before any voxel is read, so a one-byte buffer is enough. Skipped where
   * the kernel would pretend to grant it (vm.overcommit_memory = 1) and under valgrind, whose
   * operator new aborts instead of throwing (OCCSEG_TEST_NO_OOM is set by that ctest). */
  const uint8_t one = 0;
  const size_t dims[3] = {(size_t)1 << 20, (size_t)1 << 20, 1};
  occseg_map *m = NULL;
  FILE *f = fopen("/proc/sys/vm/overcommit_memory", "r");
  int mode = -1;
  (void)state;
  if (f) {
    if (fscanf(f, "%d", &mode) != 1) mode = -1;
    fclose(f);
  }
  if (mode == 1 || getenv("OCCSEG_TEST_NO_OOM")) skip();
  EXPECT_FAIL(occseg_map_from_buffer(&m, &one, OCCSEG_U8, dims, NULL, 1.0), OCCSEG_ENOMEM, "out of memory");
  assert_null(m);
}

static void bad_values_name_the_first_voxel(void **state) {
  float p[64];
  double d[64];
  float out[64];
  occseg_map *m = NULL;
  int i;
  (void)state;
  for (i = 0; i < 64; ++i) p[i] = 0.5f;
  p[63] = 2.0f;               /* voxel (3, 3, 3) */
  p[1 + 4 * (2 + 4 * 3)] = NAN; /* voxel (1, 2, 3): first in x-fastest order */
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, NULL, 1.0), OCCSEG_EVALUE,
              "probability at voxel (1, 2, 3) = nan is NaN");
  assert_null(m);
  p[1 + 4 * (2 + 4 * 3)] = 0.5f;
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, NULL, 1.0), OCCSEG_EVALUE,
              "voxel (3, 3, 3) = 2 is outside [0, 1]");
  p[63] = -0.25f;
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, NULL, 1.0), OCCSEG_EVALUE, "= -0.25 is outside [0, 1]");
  p[2] = -INFINITY; /* voxel (2, 0, 0) */
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, k444, NULL, 1.0), OCCSEG_EVALUE,
              "voxel (2, 0, 0) = -inf is infinite");
  /* F64 is checked before it is narrowed: 1 + 1e-12 would round to 1.0f. */
  for (i = 0; i < 64; ++i) d[i] = 0.5;
  d[5] = 1.0 + 1e-12; /* voxel (1, 1, 0) */
  EXPECT_FAIL(occseg_map_from_buffer(&m, d, OCCSEG_F64, k444, NULL, 1.0), OCCSEG_EVALUE,
              "voxel (1, 1, 0) = 1 is outside [0, 1]");

  /* The documented options: clamp, and NaN as unknown. */
  assert_int_equal(occseg_map_from_buffer_flags(&m, p, OCCSEG_F32, k444, NULL, 1.0, OCCSEG_IMPORT_CLAMP), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 64), OCCSEG_OK);
  assert_true(out[2] == 0.0f && out[63] == 0.0f && out[0] == 0.5f);
  occseg_map_free(m);
  p[10] = INFINITY;
  p[11] = 7.0f;
  p[12] = NAN;
  EXPECT_FAIL(occseg_map_from_buffer_flags(&m, p, OCCSEG_F32, k444, NULL, 1.0, OCCSEG_IMPORT_CLAMP), OCCSEG_EVALUE,
              "voxel (0, 3, 0) = nan is NaN");
  EXPECT_FAIL(occseg_map_from_buffer_flags(&m, p, OCCSEG_F32, k444, NULL, 1.0, OCCSEG_IMPORT_NAN_UNKNOWN),
              OCCSEG_EVALUE, "voxel (2, 0, 0) = -inf is infinite");
  assert_int_equal(occseg_map_from_buffer_flags(&m, p, OCCSEG_F32, k444, NULL, 1.0,
                                                OCCSEG_IMPORT_CLAMP | OCCSEG_IMPORT_NAN_UNKNOWN),
                   OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 64), OCCSEG_OK);
  assert_true(out[10] == 1.0f && out[11] == 1.0f && out[12] == 0.5f && out[2] == 0.0f);
  occseg_map_free(m);
  assert_int_equal(occseg_map_from_buffer_flags(&m, d, OCCSEG_F64, k444, NULL, 1.0, OCCSEG_IMPORT_CLAMP), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, 64), OCCSEG_OK);
  assert_true(out[5] == 1.0f);
  occseg_map_free(m);
}

/* A ROS nav_msgs/OccupancyGrid as it comes (int8, -1 unknown, 0..100 percent, row 0 at the
 * origin): a room of 40 x 30 cells, unknown outside, a wall of 100, free inside (0 and some 5 %
 * cells) and a box of 90 near the largest y. */
static void occupancy_grid_room(int8_t *cells) {
  size_t x, y;
  for (y = 0; y < 30; ++y)
    for (x = 0; x < 40; ++x) {
      int8_t v = -1;
      if (x >= 3 && x <= 36 && y >= 2 && y <= 27) v = (x == 3 || x == 36 || y == 2 || y == 27) ? 100 : ((x * y) % 7 ? 0 : 5);
      if (x >= 10 && x < 16 && y >= 20 && y < 24) v = 90;
      cells[y * 40 + x] = v;
    }
}

static void occupancy_grid_segments(void **state) {
  static int8_t cells[40 * 30];
  const size_t dims[3] = {40, 30, 1};
  const double origin[3] = {-2.0, -1.5, 0.0};
  occseg_map *m = NULL;
  occseg_result *r = NULL;
  occseg_params *p = NULL;
  float values[40 * 30];
  uint32_t i, counts[3] = {0, 0, 0};
  char texture[16];
  occseg_segment_info box = {0};
  (void)state;
  occupancy_grid_room(cells);
  assert_int_equal(occseg_map_from_buffer(&m, cells, OCCSEG_I8_OCCUPANCY, dims, NULL, 0.05), OCCSEG_OK);
  assert_int_equal(occseg_map_set_origin(m, origin), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, values, 40 * 30), OCCSEG_OK);
  assert_true(values[0] == 0.5f && values[2 * 40 + 3] == 1.0f && values[21 * 40 + 12] == 0.9f);
  assert_true(values[5 * 40 + 5] == 0.0f && values[7 * 40 + 4] == (float)(5 / 100.0));
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_get_string(p, "texture", texture, sizeof texture, NULL), OCCSEG_OK);
  assert_string_equal(texture, "auto"); /* lbp8 on this one-layer map */
  assert_int_equal(occseg_segment(&r, m, p), OCCSEG_OK);
  for (i = 0; i < occseg_result_segment_count(r); ++i) {
    occseg_segment_info s = {0};
    s.struct_size = sizeof s;
    assert_int_equal(occseg_result_segment(r, i, &s), OCCSEG_OK);
    counts[s.state]++;
    if (s.state == OCCSEG_OCCUPIED && s.voxels == 24) box = s;
  }
  assert_int_equal(counts[OCCSEG_FREE], 1);
  assert_int_equal(counts[OCCSEG_UNKNOWN], 1);
  assert_int_equal(counts[OCCSEG_OCCUPIED], 2); /* the wall and the box */
  assert_int_equal(box.voxels, 24);
  assert_true(box.bbox_min[0] == 10 && box.bbox_max[0] == 15 && box.bbox_min[1] == 20 && box.bbox_max[1] == 23);
  occseg_result_free(r);
  occseg_params_free(p);
  occseg_map_free(m);

  /* Read through strides: the same grid stored top row first (as an image) and flipped back. */
  {
    static int8_t flipped[40 * 30];
    const ptrdiff_t strides[3] = {1, -40, 0};
    float again[40 * 30];
    size_t y;
    for (y = 0; y < 30; ++y) memcpy(flipped + (29 - y) * 40, cells + y * 40, 40);
    assert_int_equal(occseg_map_from_buffer(&m, flipped + 29 * 40, OCCSEG_I8_OCCUPANCY, dims, strides, 0.05), OCCSEG_OK);
    assert_int_equal(occseg_map_values(m, again, 40 * 30), OCCSEG_OK);
    assert_memory_equal(again, values, sizeof values);
    occseg_map_free(m);
  }

  /* Any value but -1 and 0..100 fails, naming the first such cell (x fastest); no flag accepts it. */
  cells[29 * 40 + 39] = -2;
  cells[12 * 40 + 7] = 101;
  EXPECT_FAIL(occseg_map_from_buffer(&m, cells, OCCSEG_I8_OCCUPANCY, dims, NULL, 0.05), OCCSEG_EVALUE,
              "OccupancyGrid cell (7, 12, 0) = 101 is neither -1 (unknown) nor an occupancy in 0..100");
  assert_null(m);
  EXPECT_FAIL(occseg_map_from_buffer_flags(&m, cells, OCCSEG_I8_OCCUPANCY, dims, NULL, 0.05,
                                           OCCSEG_IMPORT_CLAMP | OCCSEG_IMPORT_NAN_UNKNOWN),
              OCCSEG_EVALUE, "(7, 12, 0) = 101");
  cells[12 * 40 + 7] = -128;
  EXPECT_FAIL(occseg_map_from_buffer(&m, cells, OCCSEG_I8_OCCUPANCY, dims, NULL, 0.05), OCCSEG_EVALUE,
              "cell (7, 12, 0) = -128");
  assert_null(m);
}

static void npy_files(void **state) {
  float p[24], out[24];
  occseg_map *m = NULL, *r = (occseg_map *)&r;
  size_t dims[3];
  double vs;
  int i;
  FILE *f;
  (void)state;
  for (i = 0; i < 24; ++i) p[i] = (float)i / 23.0f;
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, (const size_t[3]){2, 3, 4}, NULL, 0.3), OCCSEG_OK);
  assert_int_equal(occseg_map_write(m, "c_suite_map.npy"), OCCSEG_OK);
  assert_int_equal(occseg_map_read(&r, "c_suite_map.npy"), OCCSEG_OK);
  assert_int_equal(occseg_map_dims(r, dims), OCCSEG_OK);
  assert_true(dims[0] == 2 && dims[1] == 3 && dims[2] == 4);
  assert_int_equal(occseg_map_voxel_size(r, &vs), OCCSEG_OK);
  assert_true(vs == 1.0); /* .npy holds no voxel size */
  assert_int_equal(occseg_map_values(r, out, 24), OCCSEG_OK);
  assert_memory_equal(out, p, sizeof p);
  occseg_map_free(r);

  r = (occseg_map *)&r;
  EXPECT_FAIL(occseg_map_read(&r, "no/such/dir/map.npy"), OCCSEG_EIO, "cannot open 'no/such/dir/map.npy'");
  assert_null(r);
  f = fopen("c_suite_garbage.npy", "wb");
  assert_non_null(f);
  fputs("this is not numpy data at all", f);
  fclose(f);
  EXPECT_FAIL(occseg_map_read(&r, "c_suite_garbage.npy"), OCCSEG_EFORMAT, "wrong magic");
  EXPECT_FAIL(occseg_map_read(&r, NULL), OCCSEG_EINVAL, "'path'");
  EXPECT_FAIL(occseg_map_read(NULL, "c_suite_map.npy"), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_map_write(m, "no/such/dir/map.npy"), OCCSEG_EIO, "no/such/dir/map.npy");
  EXPECT_FAIL(occseg_map_write(NULL, "x.npy"), OCCSEG_EINVAL, "'map'");
  EXPECT_FAIL(occseg_map_write(m, NULL), OCCSEG_EINVAL, "'path'");
  occseg_map_free(m);
}

/* The whole text of a file (NUL-terminated; the caller frees it). */
static char *slurp_text(const char *path) {
  FILE *f = fopen(path, "rb");
  char *b;
  long n;
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  n = ftell(f);
  fseek(f, 0, SEEK_SET);
  b = malloc((size_t)n + 1);
  assert_non_null(b);
  assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
  b[n] = '\0';
  fclose(f);
  return b;
}

/* A map read from an LPS .nrrd (3D Slicer's default space) is written back in LPS with the same
 * origin and directions: written as RAS with the same numbers it came out mirrored in x and y. */
static void nrrd_files_keep_their_space(void **state) {
  static const char header[] =
      "NRRD0004\ntype: float\ndimension: 3\nSpace: LPS\nsizes: 4 3 2\n"
      "space directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\nkinds: domain domain domain\nendian: little\n"
      "encoding: raw\nspace origin: (10.25,-20.5,3)\n\n";
  float p[24], out[24];
  double origin[3];
  occseg_map *m = NULL, *r = NULL;
  char *text;
  FILE *f;
  int i;
  (void)state;
  for (i = 0; i < 24; ++i) p[i] = (float)i / 23.0f;
  f = fopen("c_suite_lps.nrrd", "wb");
  assert_non_null(f);
  fputs(header, f);
  fwrite(p, sizeof p[0], 24, f);
  fclose(f);
  assert_int_equal(occseg_map_read(&m, "c_suite_lps.nrrd"), OCCSEG_OK);
  assert_int_equal(occseg_map_origin(m, origin), OCCSEG_OK); /* the corner, in LPS coordinates */
  assert_true(origin[0] == 10.0 && origin[1] == -20.75 && origin[2] == 2.75);
  assert_int_equal(occseg_map_write(m, "c_suite_lps_out.nrrd"), OCCSEG_OK);
  text = slurp_text("c_suite_lps_out.nrrd");
  assert_non_null(strstr(text, "\nspace: left-posterior-superior\n"));
  assert_non_null(strstr(text, "\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\n"));
  assert_non_null(strstr(text, "\nspace origin: (10.25,-20.5,3)\n"));
  free(text);
  assert_int_equal(occseg_map_read(&r, "c_suite_lps_out.nrrd"), OCCSEG_OK);
  assert_int_equal(occseg_map_values(r, out, 24), OCCSEG_OK);
  assert_memory_equal(out, p, sizeof p);
  occseg_map_free(r);
  occseg_map_free(m);
  /* A map of no named space is written in RAS, occseg's world as 3D Slicer shows it. */
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, (const size_t[3]){4, 3, 2}, NULL, 0.5), OCCSEG_OK);
  assert_int_equal(occseg_map_write(m, "c_suite_ras.nrrd"), OCCSEG_OK);
  text = slurp_text("c_suite_ras.nrrd");
  assert_non_null(strstr(text, "\nspace: right-anterior-superior\n"));
  free(text);
  occseg_map_free(m);
}

int run_map_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(dtypes_map_onto_probabilities),
      cmocka_unit_test(accessors),
      cmocka_unit_test(argument_errors),
      cmocka_unit_test(out_of_memory_is_reported),
      cmocka_unit_test(bad_values_name_the_first_voxel),
      cmocka_unit_test(occupancy_grid_segments),
      cmocka_unit_test(npy_files),
      cmocka_unit_test(nrrd_files_keep_their_space),
  };
  return cmocka_run_group_tests_name("map", tests, NULL, NULL);
}
