/* occseg_fusion_* and occseg_result_point_labels (issue 26): clouds held as arrays give the map
 * occseg_map_read_options gives for the .pcd file itself, bit for bit; bad input fails with a
 * status and a message. The real clouds are read here by a small .pcd reader of its own
 * (binary_compressed: LZF, fields one after the other), not by occseg. Own executable: it needs the
 * shared data (OCCSEG_SHARED_DATA) and the installed pcl_reader plugin. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "suite.h"

void expect_fail(int rc, int code, const char *needle, const char *file, int line) {
  const char *msg = occseg_last_error();
  if (rc != code)
    fail_msg("%s:%d: status %d (%s), expected %d (%s); last error: %s", file, line, rc, occseg_status_name(rc),
             code, occseg_status_name(code), msg);
  if (!strstr(msg, needle)) fail_msg("%s:%d: last error \"%s\" does not mention \"%s\"", file, line, msg, needle);
}

typedef struct {
  float *xyz; /* width * height points, packed x, y, z */
  size_t count, width, height;
  double origin[3], orientation[4]; /* the VIEWPOINT, as PCL keeps it (float) */
  char path[4096];
} cloud;

/* liblzf's lzf_decompress; 0 on a malformed stream. */
static size_t lzf(const unsigned char *in, size_t n, unsigned char *out, size_t cap) {
  size_t i = 0, o = 0;
  while (i < n) {
    unsigned ctrl = in[i++];
    if (ctrl < 32) {
      size_t len = ctrl + 1;
      if (i + len > n || o + len > cap) return 0;
      memcpy(out + o, in + i, len);
      i += len, o += len;
    } else {
      size_t len = ctrl >> 5, back = (size_t)(ctrl & 0x1f) << 8, k;
      if (len == 7) {
        if (i >= n) return 0;
        len += in[i++];
      }
      if (i >= n) return 0;
      back += in[i++] + 1;
      len += 2;
      if (back > o || o + len > cap) return 0;
      for (k = 0; k < len; ++k, ++o) out[o] = out[o - back];
    }
  }
  return o;
}

static void read_cloud(const char *name, cloud *c) {
  const char *dir = getenv("OCCSEG_SHARED_DATA");
  FILE *f;
  long size;
  unsigned char *bytes, *raw;
  char line[512];
  size_t at = 0, field = 0, fields = 0, i, k, offsets[3] = {0, 0, 0}, off = 0;
  uint32_t sizes[2];
  float vp[7] = {0, 0, 0, 1, 0, 0, 0};
  char names[16][16];
  unsigned field_size[16];
  if (!dir) fail_msg("OCCSEG_SHARED_DATA is not set (run through ctest)");
  snprintf(c->path, sizeof c->path, "%s/%s", dir, name);
  f = fopen(c->path, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  size = ftell(f);
  fseek(f, 0, SEEK_SET);
  bytes = malloc((size_t)size);
  assert_non_null(bytes);
  assert_int_equal(fread(bytes, 1, (size_t)size, f), (size_t)size);
  fclose(f);
  for (;;) { /* header lines up to DATA */
    size_t len = 0;
    while (at + len < (size_t)size && bytes[at + len] != '\n') ++len;
    assert_true(len < sizeof line);
    memcpy(line, bytes + at, len);
    line[len] = 0;
    at += len + 1;
    if (!strncmp(line, "FIELDS ", 7)) {
      char *t = strtok(line + 7, " ");
      for (fields = 0; t && fields < 16; t = strtok(NULL, " ")) snprintf(names[fields++], 16, "%s", t);
    } else if (!strncmp(line, "SIZE ", 5)) {
      char *t = strtok(line + 5, " ");
      for (field = 0; t && field < 16; t = strtok(NULL, " ")) field_size[field++] = (unsigned)atoi(t);
    } else if (!strncmp(line, "WIDTH ", 6)) {
      c->width = (size_t)atol(line + 6);
    } else if (!strncmp(line, "HEIGHT ", 7)) {
      c->height = (size_t)atol(line + 7);
    } else if (!strncmp(line, "VIEWPOINT ", 10)) {
      assert_int_equal(sscanf(line + 10, "%f %f %f %f %f %f %f", &vp[0], &vp[1], &vp[2], &vp[3], &vp[4], &vp[5], &vp[6]), 7);
    } else if (!strncmp(line, "DATA ", 5)) {
      assert_string_equal(line + 5, "binary_compressed");
      break;
    }
  }
  c->count = c->width * c->height;
  memcpy(sizes, bytes + at, 8);
  raw = malloc(sizes[1]);
  assert_non_null(raw);
  assert_int_equal(lzf(bytes + at + 8, sizes[0], raw, sizes[1]), sizes[1]);
  for (field = 0; field < fields; ++field) { /* fields are stored one after the other */
    for (k = 0; k < 3; ++k)
      if (!strcmp(names[field], k == 0 ? "x" : k == 1 ? "y" : "z")) offsets[k] = off;
    off += c->count * field_size[field];
  }
  c->xyz = malloc(3 * c->count * sizeof(float));
  assert_non_null(c->xyz);
  for (i = 0; i < c->count; ++i)
    for (k = 0; k < 3; ++k) memcpy(&c->xyz[3 * i + k], raw + offsets[k] + 4 * i, 4);
  for (k = 0; k < 3; ++k) c->origin[k] = vp[k];
  for (k = 0; k < 4; ++k) c->orientation[k] = vp[3 + k];
  free(raw);
  free(bytes);
}

static void same_map(const occseg_map *a, const occseg_map *b) {
  size_t da[3], db[3], n;
  double va, vb, oa[3], ob[3];
  float *pa, *pb;
  assert_int_equal(occseg_map_dims(a, da), 0);
  assert_int_equal(occseg_map_dims(b, db), 0);
  assert_memory_equal(da, db, sizeof da);
  assert_int_equal(occseg_map_voxel_size(a, &va), 0);
  assert_int_equal(occseg_map_voxel_size(b, &vb), 0);
  assert_memory_equal(&va, &vb, sizeof va);
  assert_int_equal(occseg_map_origin(a, oa), 0);
  assert_int_equal(occseg_map_origin(b, ob), 0);
  assert_memory_equal(oa, ob, sizeof oa); /* exactly */
  n = da[0] * da[1] * da[2];
  pa = malloc(n * sizeof *pa);
  pb = malloc(n * sizeof *pb);
  assert_non_null(pa);
  assert_non_null(pb);
  assert_int_equal(occseg_map_values(a, pa, n), 0);
  assert_int_equal(occseg_map_values(b, pb, n), 0);
  assert_memory_equal(pa, pb, n * sizeof *pa); /* every value, bit for bit */
  free(pa);
  free(pb);
}

static occseg_map *read_pcd_map(const cloud *c, const char *voxel_option) {
  const char *options[2];
  occseg_map *m = NULL;
  options[0] = voxel_option;
  options[1] = NULL;
  if (occseg_map_read_options(&m, c->path, options) != 0) fail_msg("reading %s: %s", c->path, occseg_last_error());
  return m;
}

/* F32 packed, and F64 with a padded stride (x, y, z, pad as PCL's PointXYZ), both equal the .pcd. */
static void check_equals_pcd(const char *name, double voxel_size, const char *voxel_option) {
  cloud c;
  occseg_fusion_options o = OCCSEG_FUSION_OPTIONS_INIT;
  occseg_fusion *f = NULL;
  occseg_map *ref, *m = NULL;
  double *wide;
  size_t i;
  memset(&c, 0, sizeof c);
  read_cloud(name, &c);
  ref = read_pcd_map(&c, voxel_option);
  o.voxel_size = voxel_size;
  assert_int_equal(occseg_fusion_new(&f, &o), 0);
  assert_int_equal(occseg_fusion_add_points(f, c.xyz, OCCSEG_F32, c.count, 0, c.origin, c.orientation), 0);
  assert_int_equal(occseg_fusion_map(&m, f), 0);
  same_map(m, ref);
  occseg_map_free(m);
  occseg_fusion_free(f);
  wide = malloc(4 * c.count * sizeof *wide);
  assert_non_null(wide);
  for (i = 0; i < c.count; ++i) {
    wide[4 * i] = c.xyz[3 * i], wide[4 * i + 1] = c.xyz[3 * i + 1], wide[4 * i + 2] = c.xyz[3 * i + 2];
    wide[4 * i + 3] = 1.0;
  }
  f = NULL, m = NULL;
  assert_int_equal(occseg_fusion_new(&f, &o), 0);
  assert_int_equal(occseg_fusion_add_points(f, wide, OCCSEG_F64, c.count, 4 * sizeof(double), c.origin, c.orientation), 0);
  assert_int_equal(occseg_fusion_map(&m, f), 0);
  same_map(m, ref);
  occseg_map_free(m);
  occseg_fusion_free(f);
  free(wide);
  occseg_map_free(ref);
  free(c.xyz);
}

static void test_table_scene_equals_pcd(void **state) {
  (void)state;
  check_equals_pcd("table_scene_mug_stereo_textured.pcd", 0.02, "voxel_size=0.02");
}

static void test_office_equals_pcd(void **state) {
  (void)state;
  check_equals_pcd("office1.pcd", 0.05, "voxel_size=0.05");
}

static void test_fusion_bad_input(void **state) {
  const float p[6] = {1, 0, 0, 0, 1, 0};
  const float nan3[3] = {NAN, 0, 0};
  const double nan_origin[3] = {NAN, 0, 0}, zero_q[4] = {0, 0, 0, 0}, inf_q[4] = {1, INFINITY, 0, 0};
  const double far[3] = {6e7, 6e7, 0};
  occseg_fusion_options o = OCCSEG_FUSION_OPTIONS_INIT, d;
  occseg_fusion *f = NULL;
  occseg_map *m = (occseg_map *)&o; /* set to NULL on failure */
  uint64_t scans = 9, points = 9;
  (void)state;
  occseg_fusion_options_init(&d); /* the macro's values (fields compared: the struct has padding) */
  assert_int_equal(d.struct_size, sizeof d);
  assert_int_equal(o.struct_size, d.struct_size);
  assert_int_equal(o.threads, d.threads);
  assert_true(o.voxel_size == d.voxel_size && d.voxel_size == 0.05);
  assert_true(o.margin == d.margin && o.max_range == d.max_range && d.max_range < 0);
  assert_int_equal(o.use_box, d.use_box);
  occseg_fusion_options_init(NULL);
  EXPECT_FAIL(occseg_fusion_new(NULL, NULL), OCCSEG_EINVAL, "'out'");
  o.voxel_size = 0;
  EXPECT_FAIL(occseg_fusion_new(&f, &o), OCCSEG_EVALUE, "voxel_size 0");
  assert_null(f);
  o.voxel_size = -0.1;
  EXPECT_FAIL(occseg_fusion_new(&f, &o), OCCSEG_EVALUE, "voxel_size");
  o.voxel_size = 0.05;
  o.struct_size = 8;
  EXPECT_FAIL(occseg_fusion_new(&f, &o), OCCSEG_EINVAL, "struct_size");
  o.struct_size = sizeof o;
  o.margin = -1;
  EXPECT_FAIL(occseg_fusion_new(&f, &o), OCCSEG_EINVAL, "margin");
  o.margin = 0;
  o.use_box = 1; /* an empty box */
  EXPECT_FAIL(occseg_fusion_new(&f, &o), OCCSEG_EVALUE, "bounding box");
  o.use_box = 0;
  o.max_range = NAN;
  EXPECT_FAIL(occseg_fusion_new(&f, &o), OCCSEG_EINVAL, "max_range");
  o.max_range = -1;

  assert_int_equal(occseg_fusion_new(&f, NULL), 0);
  EXPECT_FAIL(occseg_fusion_add_points(NULL, p, OCCSEG_F32, 2, 0, NULL, NULL), OCCSEG_EINVAL, "'fusion'");
  EXPECT_FAIL(occseg_fusion_add_points(f, NULL, OCCSEG_F32, 2, 0, NULL, NULL), OCCSEG_EINVAL, "'points'");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, 0, 0, NULL, NULL), OCCSEG_EINVAL, "count is 0");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_U8, 2, 0, NULL, NULL), OCCSEG_EINVAL, "dtype");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, 2, 8, NULL, NULL), OCCSEG_EINVAL, "stride 8");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, SIZE_MAX / 2, 12, NULL, NULL), OCCSEG_EINVAL, "span");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, 2, 0, nan_origin, NULL), OCCSEG_EVALUE, "sensor origin");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, 2, 0, NULL, zero_q), OCCSEG_EVALUE, "zero");
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, 2, 0, NULL, inf_q), OCCSEG_EVALUE, "orientation");
  /* only NaN: accepted, but no map */
  assert_int_equal(occseg_fusion_add_points(f, nan3, OCCSEG_F32, 1, 0, NULL, NULL), 0);
  EXPECT_FAIL(occseg_fusion_map(&m, f), OCCSEG_EVALUE, "no finite point");
  assert_null(m);
  /* a scan that would need too big a grid is refused and leaves the fusion as it was */
  assert_int_equal(occseg_fusion_add_points(f, p, OCCSEG_F32, 2, 0, NULL, NULL), 0);
  EXPECT_FAIL(occseg_fusion_add_points(f, p, OCCSEG_F32, 1, 0, far, NULL), OCCSEG_EDIMS, "voxels");
  assert_int_equal(occseg_fusion_counts(f, &scans, &points), 0);
  assert_int_equal(scans, 2);
  assert_int_equal(points, 2);
  EXPECT_FAIL(occseg_fusion_counts(NULL, &scans, &points), OCCSEG_EINVAL, "'fusion'");
  EXPECT_FAIL(occseg_fusion_map(NULL, f), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_fusion_map(&m, NULL), OCCSEG_EINVAL, "'fusion'");
  assert_int_equal(occseg_fusion_map(&m, f), 0);
  assert_string_equal(occseg_last_error(), "");
  occseg_map_free(m);
  occseg_fusion_free(f);
  occseg_fusion_free(NULL);
}

/* A non-unit quaternion is normalised, as the .pcd path normalises its VIEWPOINT. */
static void test_quaternion_normalised(void **state) {
  const float p[9] = {0.2f, 0.1f, 0.5f, -0.3f, 0.2f, 0.9f, 0.0f, -0.4f, 0.7f};
  const double unit[4] = {0, 1, 0, 0}, scaled[4] = {0, 3.5, 0, 0};
  occseg_fusion *a = NULL, *b = NULL;
  occseg_map *ma = NULL, *mb = NULL;
  (void)state;
  assert_int_equal(occseg_fusion_new(&a, NULL), 0);
  assert_int_equal(occseg_fusion_new(&b, NULL), 0);
  assert_int_equal(occseg_fusion_add_points(a, p, OCCSEG_F32, 3, 0, NULL, unit), 0);
  assert_int_equal(occseg_fusion_add_points(b, p, OCCSEG_F32, 3, 0, NULL, scaled), 0);
  assert_int_equal(occseg_fusion_map(&ma, a), 0);
  assert_int_equal(occseg_fusion_map(&mb, b), 0);
  same_map(ma, mb);
  occseg_map_free(ma);
  occseg_map_free(mb);
  occseg_fusion_free(a);
  occseg_fusion_free(b);
}

/* Point labels: the voxel's label, OCCSEG_NO_LABEL outside the grid and for NaN; bad input. */
static void test_point_labels(void **state) {
  const float p[15] = {0.05f, 0.05f, 0.05f, 0.95f, 0.95f, 0.95f, 5, 0, 0, NAN, 0, 0, -0.01f, 0.5f, 0.5f};
  const double shifted[3] = {-0.5, 0, 0};
  static float v[1000];
  const size_t dims[3] = {10, 10, 10}, other[3] = {10, 10, 1};
  occseg_map *m = NULL, *m2 = NULL;
  occseg_result *r = NULL;
  uint32_t out[5];
  size_t i;
  (void)state;
  for (i = 0; i < 1000; ++i) v[i] = 0.9f;
  assert_int_equal(occseg_map_from_buffer(&m, v, OCCSEG_F32, dims, NULL, 0.1), 0);
  assert_int_equal(occseg_map_from_buffer(&m2, v, OCCSEG_F32, other, NULL, 0.1), 0);
  assert_int_equal(occseg_segment(&r, m, NULL), 0);
  assert_int_equal(occseg_result_point_labels(r, NULL, p, OCCSEG_F32, 5, 0, NULL, NULL, out, 5), 0);
  assert_int_equal(out[0], 0);
  assert_int_equal(out[1], 0);
  assert_int_equal(out[2], OCCSEG_NO_LABEL);
  assert_int_equal(out[3], OCCSEG_NO_LABEL);
  assert_int_equal(out[4], OCCSEG_NO_LABEL);
  assert_int_equal(occseg_result_point_labels(r, m, p, OCCSEG_F32, 5, 0, shifted, NULL, out, 5), 0);
  assert_int_equal(out[0], OCCSEG_NO_LABEL);
  assert_int_equal(out[1], 0);
  /* the map's geometry counts: moved by 10 m, every point is outside */
  {
    const double o10[3] = {10, 0, 0};
    assert_int_equal(occseg_map_set_origin(m, o10), 0);
    assert_int_equal(occseg_result_point_labels(r, m, p, OCCSEG_F32, 2, 0, NULL, NULL, out, 5), 0);
    assert_int_equal(out[0], OCCSEG_NO_LABEL);
    assert_int_equal(out[1], OCCSEG_NO_LABEL);
  }
  EXPECT_FAIL(occseg_result_point_labels(NULL, NULL, p, OCCSEG_F32, 5, 0, NULL, NULL, out, 5), OCCSEG_EINVAL, "'result'");
  EXPECT_FAIL(occseg_result_point_labels(r, NULL, p, OCCSEG_F32, 5, 0, NULL, NULL, NULL, 5), OCCSEG_EINVAL, "'out'");
  EXPECT_FAIL(occseg_result_point_labels(r, NULL, p, OCCSEG_F32, 5, 0, NULL, NULL, out, 4), OCCSEG_ERANGE, "out_count 4");
  EXPECT_FAIL(occseg_result_point_labels(r, m2, p, OCCSEG_F32, 5, 0, NULL, NULL, out, 5), OCCSEG_EINVAL, "is not the map");
  EXPECT_FAIL(occseg_result_point_labels(r, NULL, p, OCCSEG_F32, 0, 0, NULL, NULL, out, 5), OCCSEG_EINVAL, "count is 0");
  occseg_result_free(r);
  occseg_map_free(m);
  occseg_map_free(m2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_table_scene_equals_pcd), cmocka_unit_test(test_office_equals_pcd),
      cmocka_unit_test(test_fusion_bad_input),       cmocka_unit_test(test_quaternion_normalised),
      cmocka_unit_test(test_point_labels),
  };
  uint32_t loaded = 0;
  if (occseg_plugins_load_default(&loaded) != 0) fprintf(stderr, "plugins: %s\n", occseg_last_error());
  return cmocka_run_group_tests_name("fusion", tests, NULL, NULL);
}
