/* Borrowed buffers: occseg_map_view_buffer against the copy of occseg_map_from_buffer_flags (bit
 * for bit, every dtype, dense and strided layouts, bad values, NULL arguments), and the labels and
 * states read in place (occseg_result_labels_view / _states_view) and their lifetime. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "suite.h"

enum { BX = 24, BY = 20, BZ = 18, BN = BX * BY * BZ };

static const size_t kDims[3] = {BX, BY, BZ};

/* A noisy scene (deterministic): free space, an occupied box, an unknown slab. */
static double scene_p(size_t x, size_t y, size_t z) {
  const uint32_t h = (uint32_t)(x * 73856093u) ^ (uint32_t)(y * 19349663u) ^ (uint32_t)(z * 83492791u);
  const double noise = (double)(h % 1000u) / 1000.0 * 0.12;
  if (x >= 4 && x < 12 && y >= 3 && y < 11 && z >= 2 && z < 10) return 0.85 + noise;
  if (y >= 15) return 0.45 + noise;
  return 0.03 + noise;
}

static size_t item_size(occseg_dtype dt) {
  return dt == OCCSEG_F64 ? 8 : dt == OCCSEG_F32 ? 4 : dt == OCCSEG_U16 ? 2 : 1;
}

/* Stores the scene's value of one voxel as dtype `dt` at `e`. */
static void store(occseg_dtype dt, unsigned char *e, double p) {
  switch (dt) {
    case OCCSEG_F32: { const float v = (float)p; memcpy(e, &v, 4); break; }
    case OCCSEG_F64: memcpy(e, &p, 8); break;
    case OCCSEG_U8: { const uint8_t v = (uint8_t)lround(p * 255.0); memcpy(e, &v, 1); break; }
    case OCCSEG_U16: { const uint16_t v = (uint16_t)lround(p * 65535.0); memcpy(e, &v, 2); break; }
    default: { const int8_t v = p >= 0.45 && p < 0.6 ? -1 : (int8_t)lround(p * 100.0); memcpy(e, &v, 1); break; }
  }
}

/* A buffer holding the scene in one of several layouts; `data` points at voxel (0, 0, 0). */
typedef struct {
  unsigned char *alloc;
  const void *data;
  ptrdiff_t strides[3];
} layout;

enum { DENSE, FORTRAN, SLICED, FLIPPED, LAYOUTS };
static const char *const kLayoutName[LAYOUTS] = {"dense", "fortran", "sliced", "flipped"};

static layout make(occseg_dtype dt, int kind) {
  layout l;
  const ptrdiff_t it = (ptrdiff_t)item_size(dt);
  size_t x, y, z, bytes;
  unsigned char *base;
  memset(&l, 0, sizeof l);
  switch (kind) {
    case DENSE: l.strides[0] = it; l.strides[1] = it * BX; l.strides[2] = it * BX * BY; break;
    case FORTRAN: l.strides[0] = it * BZ * BY; l.strides[1] = it * BZ; l.strides[2] = it; break;
    /* every second voxel along x and every third plane of a larger array (a NumPy slice a[::3, :, ::2]) */
    case SLICED: l.strides[0] = 2 * it; l.strides[1] = 2 * it * BX; l.strides[2] = 3 * 2 * it * BX * BY; break;
    default: l.strides[0] = -it; l.strides[1] = -it * BX; l.strides[2] = -it * BX * BY; break;
  }
  bytes = (size_t)(kind == SLICED ? 3 * 2 * it * BN : it * BN);
  l.alloc = calloc(bytes, 1);
  assert_non_null(l.alloc);
  base = kind == FLIPPED ? l.alloc + bytes - (size_t)it : l.alloc;
  for (z = 0; z < BZ; ++z)
    for (y = 0; y < BY; ++y)
      for (x = 0; x < BX; ++x)
        store(dt, base + (ptrdiff_t)x * l.strides[0] + (ptrdiff_t)y * l.strides[1] + (ptrdiff_t)z * l.strides[2],
              scene_p(x, y, z));
  l.data = base;
  return l;
}

static occseg_params *two_threads(void) {
  occseg_params *p = NULL;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set_int(p, "threads", 2), OCCSEG_OK);
  return p;
}

/* Asserts that two results have the same labels (`a` copied out, `b` read in place) and the same
 * segment table, field by field. */
static void assert_same_results(const occseg_result *a, const occseg_result *b, const char *what) {
  static uint32_t la[BN];
  const uint32_t *lb = NULL;
  size_t count = 0, i;
  uint32_t s, n = occseg_result_segment_count(a);
  assert_int_equal(occseg_result_labels(a, la, BN), OCCSEG_OK);
  assert_int_equal(occseg_result_labels_view(b, &lb, &count), OCCSEG_OK);
  assert_non_null(lb);
  assert_int_equal(count, BN);
  for (i = 0; i < BN; ++i)
    if (la[i] != lb[i]) fail_msg("%s: label %u differs: %u vs %u", what, (unsigned)i, (unsigned)la[i], (unsigned)lb[i]);
  assert_int_equal(occseg_result_segment_count(b), n);
  assert_true(n > 2);  /* a scene with something in it */
  for (s = 0; s < n; ++s) {
    occseg_segment_info x, y;
    int k;
    memset(&x, 0, sizeof x);
    memset(&y, 0, sizeof y);
    x.struct_size = y.struct_size = sizeof x;
    assert_int_equal(occseg_result_segment(a, s, &x), OCCSEG_OK);
    assert_int_equal(occseg_result_segment(b, s, &y), OCCSEG_OK);
    assert_int_equal(x.id, y.id);
    assert_int_equal(x.state, y.state);
    assert_true(x.voxels == y.voxels);
    assert_memory_equal(&x.mop, &y.mop, sizeof x.mop);  /* bit for bit */
    for (k = 0; k < 3; ++k) {
      assert_int_equal(x.bbox_min[k], y.bbox_min[k]);
      assert_int_equal(x.bbox_max[k], y.bbox_max[k]);
      assert_memory_equal(&x.centroid[k], &y.centroid[k], sizeof(double));
    }
  }
}

static void view_matches_copy_every_dtype_and_layout(void **state) {
  const occseg_dtype dtypes[] = {OCCSEG_F32, OCCSEG_F64, OCCSEG_U8, OCCSEG_U16, OCCSEG_I8_OCCUPANCY};
  occseg_params *params = two_threads();
  size_t d;
  int kind;
  (void)state;
  for (d = 0; d < sizeof dtypes / sizeof dtypes[0]; ++d)
    for (kind = 0; kind < LAYOUTS; ++kind) {
      layout l = make(dtypes[d], kind);
      occseg_map *copy = NULL, *view = NULL;
      occseg_result *a = NULL, *b = NULL;
      static float va[BN], vb[BN];
      char what[64];
      snprintf(what, sizeof what, "dtype %d, %s", (int)dtypes[d], kLayoutName[kind]);
      assert_int_equal(occseg_map_from_buffer_flags(&copy, l.data, dtypes[d], kDims, l.strides, 0.05, 0), OCCSEG_OK);
      assert_int_equal(occseg_map_view_buffer(&view, l.data, dtypes[d], kDims, l.strides, 0.05, 0), OCCSEG_OK);
      /* the values read through the view are the copy's, bit for bit */
      assert_int_equal(occseg_map_values(copy, va, BN), OCCSEG_OK);
      assert_int_equal(occseg_map_values(view, vb, BN), OCCSEG_OK);
      assert_memory_equal(va, vb, sizeof va);
      assert_int_equal(occseg_segment(&a, copy, params), OCCSEG_OK);
      assert_int_equal(occseg_segment(&b, view, params), OCCSEG_OK);
      assert_same_results(a, b, what);
      occseg_result_free(a);
      occseg_result_free(b);
      occseg_map_free(copy);
      occseg_map_free(view);
      free(l.alloc);
    }
  occseg_params_free(params);
}

/* OCCSEG_IMPORT_BYTE_SWAPPED: a buffer in the opposite byte order reads as the native one, in
 * the copy path and through a view (every multi-byte dtype, every layout); and the bytes of a
 * big-endian double 0.25 (3F D0 00 .. 00), written out by hand, read as 0.25. */
static void byte_swapped_buffers_read_as_native_ones(void **state) {
  const occseg_dtype dtypes[] = {OCCSEG_F32, OCCSEG_F64, OCCSEG_U16};
  const unsigned char quarter_be[8] = {0x3F, 0xD0, 0, 0, 0, 0, 0, 0};
  const size_t one[3] = {1, 1, 1};
  occseg_params *params = two_threads();
  occseg_map *m = NULL;
  float v = 0;
  size_t d, i, k;
  int kind;
  (void)state;
  for (d = 0; d < sizeof dtypes / sizeof dtypes[0]; ++d)
    for (kind = 0; kind < LAYOUTS; ++kind) {
      layout l = make(dtypes[d], kind), sw = make(dtypes[d], kind);
      const size_t it = item_size(dtypes[d]);
      const size_t bytes = (size_t)(kind == SLICED ? 3 * 2 * it * BN : it * BN);
      occseg_map *native = NULL, *copy = NULL, *view = NULL;
      occseg_result *a = NULL, *b = NULL, *c = NULL;
      static float va[BN], vb[BN], vc[BN];
      char what[64];
      for (i = 0; i < bytes; i += it)  /* every item (at multiples of its size in each layout) */
        for (k = 0; k < it; ++k) sw.alloc[i + k] = l.alloc[i + it - 1 - k];
      snprintf(what, sizeof what, "swapped dtype %d, %s", (int)dtypes[d], kLayoutName[kind]);
      assert_int_equal(occseg_map_from_buffer_flags(&native, l.data, dtypes[d], kDims, l.strides, 0.05, 0), OCCSEG_OK);
      assert_int_equal(occseg_map_from_buffer_flags(&copy, sw.data, dtypes[d], kDims, sw.strides, 0.05,
                                                    OCCSEG_IMPORT_BYTE_SWAPPED), OCCSEG_OK);
      assert_int_equal(occseg_map_view_buffer(&view, sw.data, dtypes[d], kDims, sw.strides, 0.05,
                                              OCCSEG_IMPORT_BYTE_SWAPPED), OCCSEG_OK);
      assert_int_equal(occseg_map_values(native, va, BN), OCCSEG_OK);
      assert_int_equal(occseg_map_values(copy, vb, BN), OCCSEG_OK);
      assert_int_equal(occseg_map_values(view, vc, BN), OCCSEG_OK);
      assert_memory_equal(va, vb, sizeof va);
      assert_memory_equal(va, vc, sizeof va);
      assert_int_equal(occseg_segment(&a, native, params), OCCSEG_OK);
      assert_int_equal(occseg_segment(&b, copy, params), OCCSEG_OK);
      assert_int_equal(occseg_segment(&c, view, params), OCCSEG_OK);
      assert_same_results(a, b, what);
      assert_same_results(a, c, what);
      occseg_result_free(a);
      occseg_result_free(b);
      occseg_result_free(c);
      occseg_map_free(native);
      occseg_map_free(copy);
      occseg_map_free(view);
      free(l.alloc);
      free(sw.alloc);
    }
  occseg_params_free(params);
  assert_int_equal(occseg_map_view_buffer(&m, quarter_be, OCCSEG_F64, one, NULL, 1.0, OCCSEG_IMPORT_BYTE_SWAPPED), OCCSEG_OK);
  assert_int_equal(occseg_map_values(m, &v, 1), OCCSEG_OK);
  assert_true(v == 0.25f);
  occseg_map_free(m);
}

/* The view holds no copy: a change of the buffer between calls is what the next call reads. */
static void view_reads_the_buffer_at_each_call(void **state) {
  layout l = make(OCCSEG_F32, DENSE);
  float *p = (float *)l.alloc;
  occseg_map *view = NULL, *copy = NULL;
  occseg_result *a = NULL, *b = NULL;
  size_t i;
  (void)state;
  assert_int_equal(occseg_map_view_buffer(&view, p, OCCSEG_F32, kDims, NULL, 0.05, 0), OCCSEG_OK);
  for (i = 0; i < BN; ++i) p[i] = 1.0f - p[i];
  assert_int_equal(occseg_map_from_buffer(&copy, p, OCCSEG_F32, kDims, NULL, 0.05), OCCSEG_OK);
  assert_int_equal(occseg_segment(&a, copy, NULL), OCCSEG_OK);
  assert_int_equal(occseg_segment(&b, view, NULL), OCCSEG_OK);
  assert_same_results(a, b, "changed buffer");
  occseg_result_free(a);
  occseg_result_free(b);
  occseg_map_free(copy);
  occseg_map_free(view);
  free(l.alloc);
}

/* Copies the text of the last error after the function's name ("fn: detail" -> "detail"). */
static void detail_of_last_error(char *out, size_t size) {
  const char *m = occseg_last_error(), *c = strstr(m, ": ");
  snprintf(out, size, "%s", c ? c + 2 : m);
}

/* A bad value in a borrowed buffer: the view is made, and the call reading it fails with the
 * copy path's status and text. */
static void bad_value_as_the_copy_path(occseg_dtype dt, int kind, size_t x, size_t y, size_t z, double bad,
                                       uint32_t flags) {
  layout l = make(dt, kind);
  unsigned char *e = (unsigned char *)l.data + (ptrdiff_t)x * l.strides[0] + (ptrdiff_t)y * l.strides[1] +
                     (ptrdiff_t)z * l.strides[2];
  occseg_map *copy = NULL, *view = NULL;
  occseg_result *r = NULL;
  char expected[512], got[512];
  int rc;
  static float out[BN];
  if (dt == OCCSEG_F32) { const float v = (float)bad; memcpy(e, &v, 4); }
  else if (dt == OCCSEG_F64) memcpy(e, &bad, 8);
  else { const int8_t v = (int8_t)bad; memcpy(e, &v, 1); }
  rc = occseg_map_from_buffer_flags(&copy, l.data, dt, kDims, l.strides, 0.05, flags);
  assert_int_equal(rc, OCCSEG_EVALUE);
  assert_null(copy);
  detail_of_last_error(expected, sizeof expected);
  assert_non_null(strstr(expected, "data: "));
  assert_int_equal(occseg_map_view_buffer(&view, l.data, dt, kDims, l.strides, 0.05, flags), OCCSEG_OK);
  rc = occseg_segment(&r, view, NULL);
  assert_int_equal(rc, OCCSEG_EVALUE);
  assert_null(r);
  detail_of_last_error(got, sizeof got);
  assert_string_equal(got, expected);
  assert_non_null(strstr(occseg_last_error(), "occseg_segment: "));
  assert_int_equal(occseg_map_values(view, out, BN), OCCSEG_EVALUE);
  detail_of_last_error(got, sizeof got);
  assert_string_equal(got, expected);
  assert_int_equal(occseg_map_write(view, "borrowed_bad.npy"), OCCSEG_EVALUE);
  detail_of_last_error(got, sizeof got);
  assert_string_equal(got, expected);
  occseg_map_free(view);
  free(l.alloc);
}

static void bad_values_fail_as_in_the_copy_path(void **state) {
  (void)state;
  bad_value_as_the_copy_path(OCCSEG_F32, DENSE, 1, 2, 3, NAN, 0);  /* read where it lies */
  bad_value_as_the_copy_path(OCCSEG_F32, DENSE, 7, 19, 17, 1.5, 0);  /* in the last plane */
  bad_value_as_the_copy_path(OCCSEG_F32, DENSE, 0, 0, 0, -INFINITY, 0);
  bad_value_as_the_copy_path(OCCSEG_F32, DENSE, 5, 5, 5, NAN, OCCSEG_IMPORT_CLAMP);  /* NaN is never clamped */
  bad_value_as_the_copy_path(OCCSEG_F32, FORTRAN, 3, 4, 5, 2.0, 0);
  bad_value_as_the_copy_path(OCCSEG_F64, SLICED, 2, 3, 4, 1.0 + 1e-12, 0);  /* checked before narrowing */
  bad_value_as_the_copy_path(OCCSEG_F64, FLIPPED, 9, 9, 9, NAN, OCCSEG_IMPORT_CLAMP);
  bad_value_as_the_copy_path(OCCSEG_I8_OCCUPANCY, DENSE, 6, 1, 2, 101, OCCSEG_IMPORT_CLAMP);
}

/* The import flags fix a borrowed buffer's values as they fix a copy's. */
static void flags_apply_as_in_the_copy_path(void **state) {
  const uint32_t flags[] = {OCCSEG_IMPORT_CLAMP, OCCSEG_IMPORT_NAN_UNKNOWN, OCCSEG_IMPORT_CLAMP | OCCSEG_IMPORT_NAN_UNKNOWN};
  size_t f;
  (void)state;
  for (f = 0; f < 3; ++f) {
    int kind;
    for (kind = DENSE; kind <= FORTRAN; ++kind) {
      layout l = make(OCCSEG_F32, kind);
      float *e = (float *)((unsigned char *)l.data + 4 * l.strides[0] + 4 * l.strides[1] + 4 * l.strides[2]);
      occseg_map *copy = NULL, *view = NULL;
      occseg_result *a = NULL, *b = NULL;
      *e = (flags[f] & OCCSEG_IMPORT_CLAMP) ? 7.0f : NAN;
      assert_int_equal(occseg_map_from_buffer_flags(&copy, l.data, OCCSEG_F32, kDims, l.strides, 0.05, flags[f]),
                       OCCSEG_OK);
      assert_int_equal(occseg_map_view_buffer(&view, l.data, OCCSEG_F32, kDims, l.strides, 0.05, flags[f]), OCCSEG_OK);
      assert_int_equal(occseg_segment(&a, copy, NULL), OCCSEG_OK);
      assert_int_equal(occseg_segment(&b, view, NULL), OCCSEG_OK);
      assert_same_results(a, b, "flags");
      occseg_result_free(a);
      occseg_result_free(b);
      occseg_map_free(copy);
      occseg_map_free(view);
      free(l.alloc);
    }
  }
}

/* Every argument error of occseg_map_view_buffer is the copy path's, status and text. */
static void view_arguments_fail_as_in_the_copy_path(void **state) {
  static float p[BN];
  const size_t zero[3] = {0, 4, 4}, huge[3] = {(size_t)1 << 21, (size_t)1 << 21, 2};
  const ptrdiff_t overlap[3] = {4, 4, 4 * BX * BY};
  occseg_map *m = (occseg_map *)&m; /* must be set to NULL on failure */
  struct {
    const void *data;
    int dtype;
    const size_t *dims;
    const ptrdiff_t *strides;
    double voxel_size;
    uint32_t flags;
    int status;
  } cases[] = {
    {NULL, OCCSEG_F32, kDims, NULL, 1.0, 0, OCCSEG_EINVAL},
    {p, OCCSEG_F32, NULL, NULL, 1.0, 0, OCCSEG_EINVAL},
    {p, 99, kDims, NULL, 1.0, 0, OCCSEG_EINVAL},
    {p, OCCSEG_F32, kDims, NULL, 1.0, 8, OCCSEG_EINVAL},
    {p, OCCSEG_F32, kDims, overlap, 1.0, 0, OCCSEG_EINVAL},
    {p, OCCSEG_F32, zero, NULL, 1.0, 0, OCCSEG_EDIMS},
    {p, OCCSEG_F32, huge, NULL, 1.0, 0, OCCSEG_EDIMS},
    {p, OCCSEG_F32, kDims, NULL, 0.0, 0, OCCSEG_EVALUE},
    {p, OCCSEG_F32, kDims, NULL, NAN, 0, OCCSEG_EVALUE},
    {p, OCCSEG_F32, kDims, NULL, INFINITY, 0, OCCSEG_EVALUE},
  };
  size_t i;
  (void)state;
  for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    char expected[512], got[512];
    int dt = cases[i].dtype, rc;
    occseg_dtype dtype;
    memcpy(&dtype, &dt, sizeof dt); /* an out-of-range enum value, as a C caller may pass */
    rc = occseg_map_from_buffer_flags(&m, cases[i].data, dtype, cases[i].dims, cases[i].strides, cases[i].voxel_size,
                                      cases[i].flags);
    assert_int_equal(rc, cases[i].status);
    detail_of_last_error(expected, sizeof expected);
    m = (occseg_map *)&m;
    rc = occseg_map_view_buffer(&m, cases[i].data, dtype, cases[i].dims, cases[i].strides, cases[i].voxel_size,
                                cases[i].flags);
    assert_int_equal(rc, cases[i].status);
    assert_null(m);
    assert_non_null(strstr(occseg_last_error(), "occseg_map_view_buffer: "));
    detail_of_last_error(got, sizeof got);
    assert_string_equal(got, expected);
  }
  EXPECT_FAIL(occseg_map_view_buffer(NULL, p, OCCSEG_F32, kDims, NULL, 1.0, 0), OCCSEG_EINVAL, "'out'");
}

static void labels_states_and_table_views(void **state) {
  occseg_map *map = scene_map();
  occseg_result *r = NULL;
  const uint32_t *labels = (const uint32_t *)&r, *again = NULL;
  const uint8_t *states = (const uint8_t *)&r, *states2 = NULL;
  size_t count = 7, i, n = (size_t)SCENE_NX * SCENE_NY * SCENE_NZ;
  uint32_t *copied = malloc(n * sizeof *copied);
  uint8_t *copied_states = malloc(n);
  (void)state;
  assert_non_null(copied);
  assert_non_null(copied_states);
  /* NULL arguments: OCCSEG_EINVAL, outputs cleared */
  EXPECT_FAIL(occseg_result_labels_view(NULL, &labels, &count), OCCSEG_EINVAL, "'result'");
  assert_null(labels);
  assert_int_equal(count, 0);
  assert_int_equal(occseg_segment(&r, map, NULL), OCCSEG_OK);
  EXPECT_FAIL(occseg_result_labels_view(r, NULL, &count), OCCSEG_EINVAL, "'out'");
  labels = (const uint32_t *)&r;
  EXPECT_FAIL(occseg_result_labels_view(r, &labels, NULL), OCCSEG_EINVAL, "'count'");
  assert_null(labels);
  EXPECT_FAIL(occseg_result_states_view(NULL, &states, &count), OCCSEG_EINVAL, "'result'");
  assert_null(states);
  EXPECT_FAIL(occseg_result_states_view(r, NULL, &count), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_result_states_view(r, &states, NULL), OCCSEG_EINVAL, "'count'");
  /* the views equal the copies, and are the same memory at every call */
  assert_int_equal(occseg_result_labels_view(r, &labels, &count), OCCSEG_OK);
  assert_string_equal(occseg_last_error(), "");
  assert_int_equal(count, n);
  assert_int_equal(occseg_result_labels(r, copied, n), OCCSEG_OK);
  assert_memory_equal(labels, copied, n * sizeof *copied);
  assert_int_equal(occseg_result_labels_view(r, &again, &count), OCCSEG_OK);
  assert_ptr_equal(labels, again);
  assert_int_equal(occseg_result_states_view(r, &states, &count), OCCSEG_OK);
  assert_int_equal(count, n);
  assert_int_equal(occseg_result_states(r, copied_states, n), OCCSEG_OK);
  assert_memory_equal(states, copied_states, n);
  assert_int_equal(occseg_result_states_view(r, &states2, &count), OCCSEG_OK);
  assert_ptr_equal(states, states2);
  for (i = 0; i < n; ++i) assert_true(states[i] <= OCCSEG_OCCUPIED);
  {
    const occseg_segment_info *table = (const occseg_segment_info *)&r, *table2 = NULL;
    uint32_t s;
    EXPECT_FAIL(occseg_result_segments_view(NULL, &table, &count), OCCSEG_EINVAL, "'result'");
    assert_null(table);
    EXPECT_FAIL(occseg_result_segments_view(r, NULL, &count), OCCSEG_EINVAL, "'out'");
    EXPECT_FAIL(occseg_result_segments_view(r, &table, NULL), OCCSEG_EINVAL, "'count'");
    assert_int_equal(occseg_result_segments_view(r, &table, &count), OCCSEG_OK);
    assert_int_equal(count, occseg_result_segment_count(r));
    assert_true(count >= 3);
    for (s = 0; s < count; ++s) {
      occseg_segment_info one;
      memset(&one, 0, sizeof one);
      one.struct_size = sizeof one;
      assert_int_equal(occseg_result_segment(r, s, &one), OCCSEG_OK);
      assert_memory_equal(&one, &table[s], sizeof one);
    }
    assert_int_equal(occseg_result_segments_view(r, &table2, &count), OCCSEG_OK);
    assert_ptr_equal(table, table2);
  }
  occseg_result_free(r); /* the views end here (valgrind's run of this suite would see a late read) */
  occseg_map_free(map);
  free(copied);
  free(copied_states);
}

/* A recycled result's labels view ends with the recycle: the context's next call writes its own
 * labels into that very array. */
static void labels_view_ends_at_recycle(void **state) {
  occseg_map *map = scene_map();
  occseg_context *ctx = NULL;
  occseg_result *r = NULL;
  const uint32_t *first = NULL, *second = NULL;
  size_t count = 0;
  (void)state;
  assert_int_equal(occseg_context_new(&ctx, 2), OCCSEG_OK);
  assert_int_equal(occseg_context_segment(&r, ctx, map, NULL), OCCSEG_OK);
  assert_int_equal(occseg_result_labels_view(r, &first, &count), OCCSEG_OK);
  occseg_context_recycle(ctx, r);
  assert_int_equal(occseg_context_segment(&r, ctx, map, NULL), OCCSEG_OK);
  assert_int_equal(occseg_result_labels_view(r, &second, &count), OCCSEG_OK);
  assert_ptr_equal(first, second);
  occseg_result_free(r);
  occseg_context_free(ctx);
  occseg_map_free(map);
}

int run_borrow_tests(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(view_matches_copy_every_dtype_and_layout),
    cmocka_unit_test(view_reads_the_buffer_at_each_call),
    cmocka_unit_test(byte_swapped_buffers_read_as_native_ones),
    cmocka_unit_test(bad_values_fail_as_in_the_copy_path),
    cmocka_unit_test(flags_apply_as_in_the_copy_path),
    cmocka_unit_test(view_arguments_fail_as_in_the_copy_path),
    cmocka_unit_test(labels_states_and_table_views),
    cmocka_unit_test(labels_view_ends_at_recycle),
  };
  return cmocka_run_group_tests_name("borrow", tests, NULL, NULL);
}
