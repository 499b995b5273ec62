/* occseg_map_from_buffer with explicit strides: views that must work and layouts that must not. */
#include <stdlib.h>

#include "suite.h"

enum { NX = 3, NY = 4, NZ = 5, N = NX * NY * NZ };

/* Logical value of voxel (x, y, z): distinct for every voxel and exact in float. */
static float value(size_t x, size_t y, size_t z) { return (float)(x + NX * (y + NY * z)) / 64.0f; }

/* Asserts that `m` holds value(x, y, z) at every voxel, then frees it. */
static void check_and_free(occseg_map *m) {
  float out[N];
  size_t x, y, z, dims[3];
  assert_int_equal(occseg_map_dims(m, dims), OCCSEG_OK);
  assert_true(dims[0] == NX && dims[1] == NY && dims[2] == NZ);
  assert_int_equal(occseg_map_values(m, out, N), OCCSEG_OK);
  for (z = 0; z < NZ; ++z)
    for (y = 0; y < NY; ++y)
      for (x = 0; x < NX; ++x) assert_true(out[x + NX * (y + NY * z)] == value(x, y, z));
  occseg_map_free(m);
}

static const size_t kDims[3] = {NX, NY, NZ};

static void dense_and_explicit_dense_agree(void **state) {
  float p[N] = {0};
  size_t i;
  const ptrdiff_t s[3] = {4, 4 * NX, 4 * NX * NY};
  occseg_map *m = NULL;
  (void)state;
  for (i = 0; i < N; ++i) p[i] = (float)i / 64.0f;
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, NULL, 1.0), OCCSEG_OK);
  check_and_free(m);
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, s, 1.0), OCCSEG_OK);
  check_and_free(m);
}

static void fortran_order(void **state) {
  /* x slowest: element (x, y, z) at z + NZ * (y + NY * x). */
  double p[N];
  size_t x, y, z;
  const ptrdiff_t s[3] = {8 * NZ * NY, 8 * NZ, 8};
  occseg_map *m = NULL;
  (void)state;
  for (z = 0; z < NZ; ++z)
    for (y = 0; y < NY; ++y)
      for (x = 0; x < NX; ++x) p[z + NZ * (y + NY * x)] = value(x, y, z);
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F64, kDims, s, 1.0), OCCSEG_OK);
  check_and_free(m);
}

static void negative_strides_flip(void **state) {
  /* Stored flipped along every axis; data points at voxel (0, 0, 0), the last element. */
  float p[N] = {0};
  size_t x, y, z;
  const ptrdiff_t s[3] = {-4, -4 * NX, -4 * NX * NY};
  occseg_map *m = NULL;
  (void)state;
  for (z = 0; z < NZ; ++z)
    for (y = 0; y < NY; ++y)
      for (x = 0; x < NX; ++x) p[(NX - 1 - x) + NX * ((NY - 1 - y) + NY * (NZ - 1 - z))] = value(x, y, z);
  assert_int_equal(occseg_map_from_buffer(&m, &p[N - 1], OCCSEG_F32, kDims, s, 1.0), OCCSEG_OK);
  check_and_free(m);
}

static void padded_unaligned_uint16(void **state) {
  /* Rows padded to 7 elements, planes to 40 rows' worth, one byte off any alignment. */
  unsigned char *buf = calloc(1 + 2 * 7 * 40 * NZ, 1);
  size_t x, y, z;
  const ptrdiff_t s[3] = {2, 2 * 7, 2 * 7 * 40};
  occseg_map *m = NULL;
  float out[N];
  (void)state;
  assert_non_null(buf);
  for (z = 0; z < NZ; ++z)
    for (y = 0; y < NY; ++y)
      for (x = 0; x < NX; ++x) {
        const uint16_t v = (uint16_t)(1000 * (x + NX * (y + NY * z)));
        memcpy(buf + 1 + x * s[0] + y * s[1] + z * s[2], &v, 2);
      }
  assert_int_equal(occseg_map_from_buffer(&m, buf + 1, OCCSEG_U16, kDims, s, 1.0), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, N), OCCSEG_OK);
  for (x = 0; x < N; ++x) assert_true(out[x] == (float)(1000.0 * x / 65535.0));
  occseg_map_free(m);
  free(buf);
}

static void single_voxel_axes_ignore_strides(void **state) {
  float p[NX];
  const size_t dims[3] = {NX, 1, 1};
  const ptrdiff_t s[3] = {4, 0, PTRDIFF_MIN};
  occseg_map *m = NULL;
  float out[NX];
  (void)state;
  p[0] = 0.1f, p[1] = 0.2f, p[2] = 0.3f;
  assert_int_equal(occseg_map_from_buffer(&m, p, OCCSEG_F32, dims, s, 1.0), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, out, NX), OCCSEG_OK);
  assert_memory_equal(out, p, sizeof p);
  occseg_map_free(m);
}

static void overlapping_strides_are_rejected(void **state) {
  float p[N] = {0};
  occseg_map *m = (occseg_map *)&m;
  const ptrdiff_t zero[3] = {4, 0, 4 * NX * NY};          /* every row the same */
  const ptrdiff_t narrow[3] = {2, 2 * NX, 2 * NX * NY};    /* 4-byte items 2 bytes apart */
  const ptrdiff_t short_rows[3] = {4, 8, 4 * NX * NY};     /* rows of 12 bytes, 8 apart */
  const ptrdiff_t same[3] = {4, 4, 4 * NX * NY};           /* x and y on the same bytes */
  const ptrdiff_t reversed_overlap[3] = {-4, -8, 64 * 4};  /* |stride| 8 < 12-byte rows */
  (void)state;
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, zero, 1.0), OCCSEG_EINVAL,
              "strides[1] = 0 makes voxels overlap");
  assert_null(m);
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, narrow, 1.0), OCCSEG_EINVAL,
              "strides[0] = 2 makes voxels overlap");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, short_rows, 1.0), OCCSEG_EINVAL,
              "strides[1] = 8 makes voxels overlap");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, same, 1.0), OCCSEG_EINVAL, "makes voxels overlap");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, reversed_overlap, 1.0), OCCSEG_EINVAL,
              "strides[1] = -8 makes voxels overlap");
}

static void overflowing_strides_are_rejected(void **state) {
  float p[N] = {0};
  occseg_map *m = NULL;
  const ptrdiff_t huge[3] = {4, 4 * NX, PTRDIFF_MAX / 2};
  const ptrdiff_t minimum[3] = {4, PTRDIFF_MIN, 4 * NX * NY};
  (void)state;
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, huge, 1.0), OCCSEG_EINVAL,
              "makes the map span more bytes than an address can hold");
  EXPECT_FAIL(occseg_map_from_buffer(&m, p, OCCSEG_F32, kDims, minimum, 1.0), OCCSEG_EINVAL, "overflows");
}

int run_strides_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(dense_and_explicit_dense_agree),   cmocka_unit_test(fortran_order),
      cmocka_unit_test(negative_strides_flip),            cmocka_unit_test(padded_unaligned_uint16),
      cmocka_unit_test(single_voxel_axes_ignore_strides), cmocka_unit_test(overlapping_strides_are_rejected),
      cmocka_unit_test(overflowing_strides_are_rejected),
  };
  return cmocka_run_group_tests_name("strides", tests, NULL, NULL);
}
