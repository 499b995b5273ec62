/*
 * Plugins through the installed C API, as a user's program meets them. One scenario per run
 * (each needs a fresh process: plugins stay loaded):
 *   test_plugins example EXAMPLE_SO WORKDIR   the example plugin: listing, parameters, stages, .occtxt
 *   test_plugins errors BROKEN_DIR            every way loading can fail leaves the registry unchanged
 *   test_plugins default                      occseg_plugins_load_default over OCCSEG_PLUGIN_PATH
 *   test_plugins default_broken               the same over a folder of broken plugins
 *   test_plugins octomap FILE.bt              the installed OctoMap reader plugin, found by itself
 *   test_plugins pcd FILE.pcd                 the installed PCL reader plugin
 *   test_plugins auto FILE.bt WORKDIR         no load call: the first read of .bt loads the search path
 *   test_plugins auto_off FILE.bt             the same with OCCSEG_NO_DEFAULT_PLUGINS=1: nothing loads
 *   test_plugins first_write WORKDIR          the built-in readers/writers serve the first call that uses them
 *   test_plugins first_load EXAMPLE_SO        ... and are registered before a plugin loaded by the first call
 * The example scenario counts plugins around an explicit load and pins the errors of extensions
 * nothing serves before it, so it runs with OCCSEG_NO_DEFAULT_PLUGINS=1 (tests/plugins/CMakeLists.txt).
 */
#define _POSIX_C_SOURCE 200809L /* symlink, lstat */
#include <occseg/occseg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int failures = 0;

#define CHECK(cond)                                                                     \
  do {                                                                                  \
    if (!(cond)) {                                                                      \
      fprintf(stderr, "%s:%d: CHECK(%s) failed; last error: %s\n", __FILE__, __LINE__, #cond, \
              occseg_last_error());                                                     \
      ++failures;                                                                       \
    }                                                                                   \
  } while (0)

/* `call` fails with `code` and a last-error text containing every given fragment. */
static void expect_fail(int rc, int code, const char *a, const char *b, const char *c, int line) {
  const char *e = occseg_last_error();
  const char *parts[3];
  int i;
  parts[0] = a;
  parts[1] = b;
  parts[2] = c;
  if (rc != code) {
    fprintf(stderr, "line %d: expected %s, got %s (%s)\n", line, occseg_status_name(code), occseg_status_name(rc), e);
    ++failures;
  }
  for (i = 0; i < 3; ++i)
    if (parts[i] && !strstr(e, parts[i])) {
      fprintf(stderr, "line %d: last error lacks '%s': %s\n", line, parts[i], e);
      ++failures;
    }
}
#define EXPECT_FAIL(call, code, a, b, c) expect_fail((call), (code), (a), (b), (c), __LINE__)

static int find_stage(occseg_stage_kind kind, const char *name, const char *plugin) {
  uint32_t i;
  for (i = 0; i < occseg_stage_count(kind); ++i)
    if (strcmp(occseg_stage_name(kind, i), name) == 0) return strcmp(occseg_stage_plugin(kind, i), plugin) == 0;
  return 0;
}

static int find_plugin(const char *name) {
  uint32_t i;
  for (i = 0; i < occseg_plugin_count(); ++i)
    if (strcmp(occseg_plugin_name(i), name) == 0) return (int)i;
  return -1;
}

/* True when a file whose name contains `fragment` is mapped into this process. */
static int mapped(const char *fragment) {
  char line[4096];
  int found = 0;
  FILE *f = fopen("/proc/self/maps", "r");
  if (!f) return -1;
  while (fgets(line, sizeof line, f))
    if (strstr(line, fragment)) found = 1;
  fclose(f);
  return found;
}

/* A 32^3 map: free (0.1) with an occupied cube (0.9) at [8, 24)^3, plus a little texture. */
static occseg_map *cube_map(size_t n2d) {
  size_t dims[3] = {32, 32, 32}, x, y, z;
  float *v;
  occseg_map *m = NULL;
  if (n2d) dims[2] = 1;
  v = (float *)malloc(dims[0] * dims[1] * dims[2] * sizeof *v);
  for (z = 0; z < dims[2]; ++z)
    for (y = 0; y < dims[1]; ++y)
      for (x = 0; x < dims[0]; ++x) {
        const int in = x >= 8 && x < 24 && y >= 8 && y < 24 && (n2d || (z >= 8 && z < 24));
        v[x + 32 * (y + 32 * z)] = (in ? 0.9f : 0.1f) + (((x + y + z) % 2) ? 0.02f : 0.0f);
      }
  CHECK(occseg_map_from_buffer(&m, v, OCCSEG_F32, dims, NULL, 0.1) == OCCSEG_OK);
  free(v);
  return m;
}

/* Segments `m` and returns the number of voxels of occupied segments (or -1 on failure). */
static long occupied_voxels(const occseg_map *m, const occseg_params *p) {
  occseg_result *r = NULL;
  occseg_segment_info info;
  uint32_t i;
  long total = 0;
  if (occseg_segment(&r, m, p) != OCCSEG_OK) return -1;
  for (i = 0; i < occseg_result_segment_count(r); ++i) {
    info.struct_size = sizeof info;
    CHECK(occseg_result_segment(r, i, &info) == OCCSEG_OK);
    if (info.state == OCCSEG_OCCUPIED) total += (long)info.voxels;
  }
  occseg_result_free(r);
  return total;
}

static void example(const char *so, const char *work) {
  uint32_t before = occseg_plugin_count(), params_before = occseg_param_count(), i, idx = 0, major = 0, minor = 0;
  occseg_params *p = NULL;
  occseg_map *m = cube_map(0), *back = NULL;
  char text[256], path[4096];
  size_t len = 0, dims[3];
  double v = -1, lo = -1, hi = -1;
  int k;
  float a[32 * 32 * 32], b[32 * 32 * 32];

  /* Built-in plugins are there before anything is loaded. */
  CHECK(find_plugin("builtin") == 0 && find_plugin("builtin_io") == 1);
  CHECK(find_stage(OCCSEG_STAGE_TEXTURE, "lbp6", "builtin") && find_stage(OCCSEG_STAGE_TEXTURE, "lbp8", "builtin"));
  CHECK(find_stage(OCCSEG_STAGE_SIMILARITY, "g", "builtin") && find_stage(OCCSEG_STAGE_SIMILARITY, "chi2", "builtin"));
  CHECK(find_stage(OCCSEG_STAGE_READER, ".npy", "builtin_io") && find_stage(OCCSEG_STAGE_WRITER, ".nrrd", "builtin_io"));
  CHECK(occseg_params_create(&p) == OCCSEG_OK);
  EXPECT_FAIL(occseg_params_set(p, "texture", "lbp6ri"), OCCSEG_EINVAL, "'lbp6ri' is not a registered texture operator",
              "lbp6, lbp8", NULL);
  EXPECT_FAIL(occseg_params_set(p, "ri_flat_below", "0.5"), OCCSEG_EINVAL, "'ri_flat_below': no such parameter", NULL, NULL);
  snprintf(path, sizeof path, "%s/map.occtxt", work);
  EXPECT_FAIL(occseg_map_write(m, path), OCCSEG_EUNSUPPORTED, "no writer for extension '.occtxt'", ".npy, .nrrd", NULL);

  /* Load it: listed with its version, ABI and path; its stages and parameter appear. */
  CHECK(occseg_plugins_load(so) == OCCSEG_OK);
  CHECK(occseg_plugin_count() == before + 1);
  k = find_plugin("example");
  CHECK(k == (int)before);
  CHECK(k >= 0 && strcmp(occseg_plugin_version((uint32_t)k), "1.0.0") == 0);
  CHECK(k >= 0 && strcmp(occseg_plugin_path((uint32_t)k), so) == 0);
  CHECK(k >= 0 && strstr(occseg_plugin_description((uint32_t)k), "lbp6ri") != NULL);
  CHECK(occseg_plugin_abi((uint32_t)k, &major, &minor) == OCCSEG_OK && major == 1 && minor == 0);
  EXPECT_FAIL(occseg_plugin_abi(occseg_plugin_count(), &major, &minor), OCCSEG_ERANGE, "out of range", NULL, NULL);
  CHECK(occseg_plugin_name(occseg_plugin_count()) == NULL);
  CHECK(find_stage(OCCSEG_STAGE_TEXTURE, "lbp6ri", "example") && find_stage(OCCSEG_STAGE_SIMILARITY, "l1", "example"));
  CHECK(find_stage(OCCSEG_STAGE_READER, ".occtxt", "example") && find_stage(OCCSEG_STAGE_WRITER, ".occtxt", "example"));
  CHECK(occseg_param_count() == params_before + 1);
  CHECK(occseg_param_find("ri_flat_below", &idx) == OCCSEG_OK && idx == params_before);
  CHECK(strcmp(occseg_param_name(idx), "ri_flat_below") == 0 && strcmp(occseg_param_kind(idx), "double") == 0);
  CHECK(strcmp(occseg_param_plugin(idx), "example") == 0 && strcmp(occseg_param_plugin(0), "builtin") == 0);
  CHECK(occseg_param_bounds(idx, &lo, &hi) == OCCSEG_OK && lo == 0 && hi == 1);
  CHECK(occseg_param_default(idx, text, sizeof text, &len) == OCCSEG_OK && strcmp(text, "0") == 0 && len == 1);

  /* Its parameter works like a built-in one; bad values and unknown names stay errors. */
  CHECK(occseg_params_get_double(p, "ri_flat_below", &v) == OCCSEG_OK && v == 0);
  CHECK(occseg_params_set(p, "ri_flat_below", "0.25") == OCCSEG_OK);
  CHECK(occseg_params_get_double(p, "ri_flat_below", &v) == OCCSEG_OK && v == 0.25);
  CHECK(occseg_params_set_double(p, "ri_flat_below", 0.5) == OCCSEG_OK);
  CHECK(occseg_params_get(p, "ri_flat_below", text, sizeof text, NULL) == OCCSEG_OK && strcmp(text, "0.5") == 0);
  EXPECT_FAIL(occseg_params_set(p, "ri_flat_below", "2"), OCCSEG_EINVAL, "'ri_flat_below'", "outside [0, 1]", NULL);
  EXPECT_FAIL(occseg_params_set(p, "ri_flat_belo", "0.1"), OCCSEG_EINVAL, "no such parameter", NULL, NULL);
  CHECK(occseg_params_preset(p, "default") == OCCSEG_OK); /* a preset resets plugin parameters too */
  CHECK(occseg_params_get_double(p, "ri_flat_below", &v) == OCCSEG_OK && v == 0);

  /* Its stages run in the pipeline: the occupied cube is found with lbp6ri + l1. */
  CHECK(occupied_voxels(m, p) == 16 * 16 * 16);
  CHECK(occseg_params_set(p, "texture", "lbp6ri") == OCCSEG_OK);
  CHECK(occseg_params_set_string(p, "similarity", "l1") == OCCSEG_OK);
  CHECK(occseg_params_get_string(p, "texture", text, sizeof text, NULL) == OCCSEG_OK && strcmp(text, "lbp6ri") == 0);
  CHECK(occupied_voxels(m, p) == 16 * 16 * 16);
  CHECK(occseg_params_set(p, "ri_flat_below", "1") == OCCSEG_OK); /* every unit flat: still segments */
  CHECK(occupied_voxels(m, p) == 16 * 16 * 16);
  {
    occseg_map *flat = cube_map(1); /* lbp6ri refuses 2D maps with its own error */
    occseg_result *r = NULL;
    EXPECT_FAIL(occseg_segment(&r, flat, p), OCCSEG_EDIMS, "texture operator 'lbp6ri' (plugin 'example') failed",
                "at least 3 voxels", NULL);
    CHECK(r == NULL);
    occseg_map_free(flat);
  }

  /* Its writer and reader: a round trip through .occtxt keeps values, voxel size and origin.
   * A symbolic link planted where an earlier version put its temporary (PATH.tmp) is not
   * followed: the file it points to stays as it was, and the map is a regular file. */
  {
    const double origin[3] = {1.5, -2, 0.25};
    double o[3], vs = 0;
    char link[4200], victim[4200], got[16] = {0};
    struct stat st;
    FILE *f;
    snprintf(victim, sizeof victim, "%s/victim.txt", work);
    snprintf(link, sizeof link, "%s.tmp", path);
    remove(link);
    remove(path);
    CHECK((f = fopen(victim, "w")) != NULL && fputs("precious", f) >= 0 && fclose(f) == 0);
    CHECK(symlink(victim, link) == 0);
    CHECK(occseg_map_set_origin(m, origin) == OCCSEG_OK);
    CHECK(occseg_map_write(m, path) == OCCSEG_OK);
    CHECK((f = fopen(victim, "r")) != NULL && fread(got, 1, sizeof got - 1, f) == 8 && fclose(f) == 0);
    CHECK(strcmp(got, "precious") == 0);
    CHECK(lstat(path, &st) == 0 && S_ISREG(st.st_mode));
    remove(link);
    CHECK(occseg_map_read(&back, path) == OCCSEG_OK);
    CHECK(back && occseg_map_dims(back, dims) == OCCSEG_OK && dims[0] == 32 && dims[1] == 32 && dims[2] == 32);
    CHECK(back && occseg_map_voxel_size(back, &vs) == OCCSEG_OK && vs == 0.1);
    CHECK(back && occseg_map_origin(back, o) == OCCSEG_OK && o[0] == 1.5 && o[1] == -2 && o[2] == 0.25);
    CHECK(occseg_map_values(m, a, 32 * 32 * 32) == OCCSEG_OK);
    CHECK(back && occseg_map_values(back, b, 32 * 32 * 32) == OCCSEG_OK);
    CHECK(memcmp(a, b, sizeof a) == 0);
    occseg_map_free(back);
    back = NULL;
  }
  {
    const char *opts[] = {"voxel_size=2", NULL};
    EXPECT_FAIL(occseg_map_read_options(&back, path, opts), OCCSEG_EINVAL, "takes no options", "map.occtxt", NULL);
    CHECK(back == NULL);
  }
  snprintf(path, sizeof path, "%s/map.unknownext", work);
  EXPECT_FAIL(occseg_map_read(&back, path), OCCSEG_EUNSUPPORTED, "no reader for extension '.unknownext'", ".occtxt",
              NULL);

  /* Loading it again is an error naming the first copy, and changes nothing. */
  EXPECT_FAIL(occseg_plugins_load(so), OCCSEG_EPLUGIN, "a plugin named 'example' is already loaded", so, NULL);
  CHECK(occseg_plugin_count() == before + 1);
  for (i = 0; i < 4; ++i) CHECK(occseg_stage_name((occseg_stage_kind)i, occseg_stage_count((occseg_stage_kind)i)) == NULL);
  occseg_params_free(p);
  occseg_map_free(m);
}

static void errors(const char *dir) {
  const uint32_t plugins = occseg_plugin_count(), params = occseg_param_count();
  uint32_t counts[4], i;
  char so[4096];
  occseg_params *p = NULL;
  CHECK(occseg_params_create(&p) == OCCSEG_OK);
  for (i = 0; i < 4; ++i) counts[i] = occseg_stage_count((occseg_stage_kind)i);

#define PLUGIN(name) (snprintf(so, sizeof so, "%s/%s.so", dir, name), so)
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("does_not_exist")), OCCSEG_EPLUGIN, "cannot be loaded",
              "does_not_exist.so: cannot open shared object file", "plugin '");
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("not_a_library")), OCCSEG_EPLUGIN, "not_a_library.so': cannot be loaded",
              "not_a_library.so: ", NULL); /* + dlerror's reason, e.g. "invalid ELF header" */
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("no_entry")), OCCSEG_EPLUGIN, "no_entry.so': no entry point 'occseg_plugin_entry'",
              "undefined symbol: occseg_plugin_entry", NULL);
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("null_descriptor")), OCCSEG_EPLUGIN, "null_descriptor.so'",
              "occseg_plugin_entry() returned NULL", NULL);
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("abi_major")), OCCSEG_EPLUGIN, "abi_major.so': ABI mismatch",
              "built for plugin ABI 2.0, this host speaks 1.0", NULL);
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("abi_minor")), OCCSEG_EPLUGIN, "abi_minor.so': ABI mismatch",
              "built for plugin ABI 1.1, newer than this host's 1.0", NULL);
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("duplicate_name")), OCCSEG_EPLUGIN, "duplicate_name.so'",
              "a plugin named 'builtin' is already loaded", NULL);
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("duplicate_stage")), OCCSEG_EPLUGIN, "duplicate_stage.so'",
              "texture operator 'lbp6' is already registered by plugin 'builtin'", NULL);
  EXPECT_FAIL(occseg_plugins_load(PLUGIN("register_fails")), OCCSEG_EPLUGIN, "register_fails.so'",
              "register function of 'register_fails' failed (-1)", "deliberate failure: the licence file is missing");
  EXPECT_FAIL(occseg_plugins_load(NULL), OCCSEG_EINVAL, "'path'", NULL, NULL);

  /* Nothing of the failed plugins is visible, and their libraries were closed again. */
  CHECK(occseg_plugin_count() == plugins);
  CHECK(occseg_param_count() == params);
  for (i = 0; i < 4; ++i) CHECK(occseg_stage_count((occseg_stage_kind)i) == counts[i]);
  CHECK(!find_stage(OCCSEG_STAGE_SIMILARITY, "dup_fresh_sim", "duplicate_stage"));
  EXPECT_FAIL(occseg_params_set(p, "dup_fresh_param", "1"), OCCSEG_EINVAL, "no such parameter", NULL, NULL);
  EXPECT_FAIL(occseg_params_set(p, "fails_param", "0.5"), OCCSEG_EINVAL, "no such parameter", NULL, NULL);
  EXPECT_FAIL(occseg_params_set(p, "texture", "fails_tex"), OCCSEG_EINVAL, "not a registered texture operator", NULL, NULL);
  CHECK(mapped("duplicate_stage.so") == 0 && mapped("register_fails.so") == 0 && mapped("abi_major.so") == 0);

  /* A plugin that loads but misbehaves when run: errors name it, never a crash. */
  CHECK(occseg_plugins_load(PLUGIN("misbehaving")) == OCCSEG_OK);
  CHECK(mapped("misbehaving.so") == 1);
  {
    occseg_map *m = cube_map(0), *none = NULL;
    occseg_result *r = NULL;
    CHECK(occseg_params_set(p, "texture", "bad_codes") == OCCSEG_OK);
    EXPECT_FAIL(occseg_segment(&r, m, p), OCCSEG_EPLUGIN, "texture operator 'bad_codes' (plugin 'misbehaving')",
                "code 7 at voxel (5, 0, 0) is outside [0, 5)", NULL);
    CHECK(occseg_params_set(p, "texture", "lbp6") == OCCSEG_OK);
    CHECK(occseg_params_set(p, "similarity", "nan_sim") == OCCSEG_OK);
    EXPECT_FAIL(occseg_segment(&r, m, p), OCCSEG_EPLUGIN, "similarity 'nan_sim' (plugin 'misbehaving') returned nan",
                NULL, NULL);
    CHECK(r == NULL);
    EXPECT_FAIL(occseg_map_read(&none, "whatever.nomap"), OCCSEG_EPLUGIN, "the reader returned no map",
                "plugin 'misbehaving'", NULL);
    occseg_map_free(m);
  }
  occseg_params_free(p);
}

static void default_path(void) {
  uint32_t loaded = 99;
  char path[8192];
  const char *env = getenv("OCCSEG_PLUGIN_PATH");
  CHECK(env != NULL);
  CHECK(occseg_plugin_search_path(path, sizeof path, NULL) == OCCSEG_OK);
  CHECK(env && strncmp(path, env, strlen(env)) == 0); /* the variable's folders come first */
  CHECK(find_plugin("example") < 0);
  CHECK(occseg_plugins_load_default(&loaded) == OCCSEG_OK);
  CHECK(loaded >= 1);
  CHECK(find_plugin("example") >= 0);
  /* Again: everything is loaded already, so nothing is loaded and nothing fails. */
  CHECK(occseg_plugins_load_default(&loaded) == OCCSEG_OK && loaded == 0);
}

/* A folder of broken plugins on the search path: every file is tried, the good one loads, and
 * the failures are all reported at once. */
static void default_broken(void) {
  uint32_t loaded = 99;
  const char *e;
  EXPECT_FAIL(occseg_plugins_load_default(&loaded), OCCSEG_EPLUGIN, "abi_major.so': ABI mismatch",
              "no_entry.so': no entry point", "register_fails.so'");
  e = occseg_last_error();
  CHECK(strstr(e, "not_a_library.so': cannot be loaded") != NULL && strstr(e, "; ") != NULL);
  CHECK(strstr(e, "duplicate_name.so") == NULL); /* named like a loaded plugin: skipped, not an error */
  /* misbehaving, plus the reader plugins of the install's own folder when they are built. */
  CHECK(loaded >= 1 && find_plugin("misbehaving") >= 0);
}

static void octomap(const char *bt) {
  occseg_map *m = NULL;
  occseg_result *r = NULL;
  size_t dims[3];
  double vs = 0, o[3];
  CHECK(find_stage(OCCSEG_STAGE_READER, ".bt", "octomap_reader") == 0);
  /* The installed plugin folder is found next to the installed liboccseg (a relocated prefix). */
  CHECK(occseg_plugins_load_default(NULL) == OCCSEG_OK);
  CHECK(find_stage(OCCSEG_STAGE_READER, ".bt", "octomap_reader"));
  CHECK(occseg_map_read(&m, bt) == OCCSEG_OK);
  CHECK(m && occseg_map_voxel_size(m, &vs) == OCCSEG_OK && vs > 0.0799 && vs < 0.0801); /* 8 cm tree */
  CHECK(m && occseg_map_dims(m, dims) == OCCSEG_OK);
  CHECK(m && occseg_map_origin(m, o) == OCCSEG_OK);
  /* Occupied extent about x -8..31 m, y -7.5..7.4 m, z -0.3..2.8 m (data README): the grid spans it. */
  CHECK(m && o[0] < -7.9 && o[0] + dims[0] * vs > 30.9 && o[1] < -7.4 && o[1] + dims[1] * vs > 7.3);
  CHECK(m && o[2] < -0.2 && o[2] + dims[2] * vs > 2.7);
  CHECK(m && dims[0] < 520 && dims[1] < 200 && dims[2] < 45); /* and not much more */
  printf("geb079.bt: %zu x %zu x %zu voxels of %.3f m, origin (%.2f, %.2f, %.2f)\n", dims[0], dims[1], dims[2], vs, o[0],
         o[1], o[2]);
  {
    const char *opts[] = {"voxel_size=0.16", NULL};
    occseg_map *c = NULL;
    size_t d2[3];
    CHECK(occseg_map_read_options(&c, bt, opts) == OCCSEG_OK);
    CHECK(c && occseg_map_dims(c, d2) == OCCSEG_OK && d2[0] * 2 >= dims[0] && d2[0] * 2 <= dims[0] + 2);
    occseg_map_free(c);
  }
  {
    const char *opts[] = {"colour=red", NULL};
    occseg_map *c = NULL;
    EXPECT_FAIL(occseg_map_read_options(&c, bt, opts), OCCSEG_EINVAL, "unknown option 'colour=red'", NULL, NULL);
  }
  {
    occseg_map *c = NULL;
    EXPECT_FAIL(occseg_map_read(&c, "no/such/file.bt"), OCCSEG_EIO, "no/such/file.bt", NULL, NULL);
  }
  /* The scan graph beside it takes the pose options of the command's .graph input too. */
  {
    char graph[4096];
    const char *slash = strrchr(bt, '/');
    const char *opts[] = {"sensor_origin=0,0,0", "sensor_orientation=1,0,0,0", NULL};
    occseg_map *g = NULL;
    snprintf(graph, sizeof graph, "%.*s/spherical_scan.graph", slash ? (int)(slash - bt) : 1, slash ? bt : ".");
    CHECK(occseg_map_read_options(&g, graph, opts) == OCCSEG_OK);
    occseg_map_free(g);
  }
  /* And it segments. */
  CHECK(m && occseg_segment(&r, m, NULL) == OCCSEG_OK && occseg_result_segment_count(r) > 1);
  occseg_result_free(r);
  occseg_map_free(m);
}

static void pose_options(const char *file);

static void pcd(const char *file) {
  const char *opts[] = {"voxel_size=0.1", NULL}, *bad[] = {"voxel_size=-1", NULL};
  occseg_map *m = NULL;
  size_t dims[3];
  double vs = 0, o[3];
  CHECK(occseg_plugins_load_default(NULL) == OCCSEG_OK);
  CHECK(find_stage(OCCSEG_STAGE_READER, ".pcd", "pcl_reader"));
  CHECK(occseg_map_read_options(&m, file, opts) == OCCSEG_OK);
  CHECK(m && occseg_map_voxel_size(m, &vs) == OCCSEG_OK && vs == 0.1);
  CHECK(m && occseg_map_dims(m, dims) == OCCSEG_OK && occseg_map_origin(m, o) == OCCSEG_OK);
  /* Points 0.69 .. 2.59 m deep seen from the origin: the fitted grid holds the sensor and them. */
  CHECK(m && o[0] <= 0 && o[1] <= 0 && o[2] <= 0 && o[0] + dims[0] * vs >= 0 && o[1] + dims[1] * vs >= 0 &&
        o[2] + dims[2] * vs >= 0);
  CHECK(m && dims[2] * vs >= 2.59 && dims[2] < 40);
  printf("pcd: %zu x %zu x %zu voxels of %.2f m, origin (%.2f, %.2f, %.2f)\n", dims[0], dims[1], dims[2], vs, o[0],
         o[1], o[2]);
  occseg_map_free(m);
  m = NULL;
  EXPECT_FAIL(occseg_map_read_options(&m, file, bad), OCCSEG_EINVAL, "voxel size -1", "plugin 'pcl_reader'", NULL);
  pose_options(file);
}

/* Reads `file` with `opt` (and voxel_size=0.1); its values (malloc'd) and dims, or NULL. */
static float *read_values(const char *file, const char *opt, size_t dims[3]) {
  const char *opts[] = {"voxel_size=0.1", opt, NULL};
  occseg_map *m = NULL;
  float *v = NULL;
  if (occseg_map_read_options(&m, file, opts) == OCCSEG_OK && occseg_map_dims(m, dims) == OCCSEG_OK) {
    v = (float *)malloc(dims[0] * dims[1] * dims[2] * sizeof *v);
    if (v && occseg_map_values(m, v, dims[0] * dims[1] * dims[2]) != OCCSEG_OK) {
      free(v);
      v = NULL;
    }
  }
  occseg_map_free(m);
  return v;
}

static int same_values(const float *a, const size_t da[3], const float *b, const size_t db[3]) {
  return a && b && da[0] == db[0] && da[1] == db[1] && da[2] == db[2] &&
         memcmp(a, b, da[0] * da[1] * da[2] * sizeof *a) == 0;
}

/* sensor_origin and sensor_orientation each replace their half of the stored pose, as the
 * command's --sensor-origin and --sensor-orientation do (issue 26): the table scene is seen from
 * the origin turned 180 degrees about x (VIEWPOINT 0 0 0 0 1 0 0), so the origin alone, or that
 * turn alone, gives the stored map, and no turn another one. */
static void pose_options(const char *file) {
  size_t d0[3], d1[3], d2[3], d3[3];
  float *stored = read_values(file, NULL, d0), *origin = read_values(file, "sensor_origin=0,0,0", d1);
  float *turn = read_values(file, "sensor_orientation=0,1,0,0", d2), *none = read_values(file, "sensor_orientation=1,0,0,0", d3);
  occseg_map *m = NULL;
  const char *zero[] = {"sensor_orientation=0,0,0,0", NULL}, *three[] = {"sensor_orientation=1,0,0", NULL};
  CHECK(stored != NULL && origin != NULL && turn != NULL && none != NULL);
  CHECK(same_values(stored, d0, origin, d1));
  CHECK(same_values(stored, d0, turn, d2));
  CHECK(none && !same_values(stored, d0, none, d3));
  EXPECT_FAIL(occseg_map_read_options(&m, file, zero), OCCSEG_EINVAL, "sensor_orientation", "no rotation", NULL);
  EXPECT_FAIL(occseg_map_read_options(&m, file, three), OCCSEG_EINVAL, "sensor_orientation", "needs 4", NULL);
  CHECK(m == NULL);
  free(stored);
  free(origin);
  free(turn);
  free(none);
}

/* A program that never calls a load function reads .bt as the occseg command does: the first read
 * of an extension no loaded reader serves loads the default search path (the install's plugin
 * folder, next to the installed liboccseg), once. An extension nothing serves names itself, the
 * folders searched and what would help. */
static void auto_load(const char *bt, const char *work) {
  const uint32_t before = occseg_plugin_count();
  occseg_map *m = NULL, *none = NULL;
  size_t dims[3];
  char path[4096], search[8192];
  uint32_t after;
  CHECK(getenv("OCCSEG_NO_DEFAULT_PLUGINS") == NULL);
  CHECK(find_plugin("octomap_reader") < 0 && !find_stage(OCCSEG_STAGE_READER, ".bt", "octomap_reader"));
  CHECK(occseg_map_read(&m, bt) == OCCSEG_OK);
  CHECK(m && occseg_map_dims(m, dims) == OCCSEG_OK && dims[0] == 487 && dims[1] == 187 && dims[2] == 39);
  CHECK(find_plugin("octomap_reader") >= 0 && find_plugin("pcl_reader") >= 0);
  after = occseg_plugin_count();
  CHECK(after >= before + 2);
  occseg_map_free(m);
  /* Loaded once: later reads and misses load nothing more. */
  CHECK(occseg_map_read(&m, bt) == OCCSEG_OK);
  occseg_map_free(m);
  CHECK(occseg_plugin_search_path(search, sizeof search, NULL) == OCCSEG_OK);
  snprintf(path, sizeof path, "%s/map.nosuchformat", work);
  EXPECT_FAIL(occseg_map_read(&none, path), OCCSEG_EUNSUPPORTED, "no reader for extension '.nosuchformat'",
              "occseg_plugins_load(", "OCCSEG_PLUGIN_PATH");
  CHECK(strstr(occseg_last_error(), search) != NULL); /* the folders that were searched */
  CHECK(none == NULL);
  {
    occseg_map *c = cube_map(0);
    snprintf(path, sizeof path, "%s/map.occtxt", work);
    EXPECT_FAIL(occseg_map_write(c, path), OCCSEG_EUNSUPPORTED, "no writer for extension '.occtxt'",
                "no plugin of the default search path", "occseg_plugins_load(");
    occseg_map_free(c);
  }
  CHECK(occseg_plugin_count() == after);
}

/* With OCCSEG_NO_DEFAULT_PLUGINS=1 nothing is loaded behind the caller's back: the error says why
 * and which call loads the plugins, and that call then works. */
static void auto_off(const char *bt) {
  const uint32_t before = occseg_plugin_count();
  occseg_map *m = NULL;
  CHECK(getenv("OCCSEG_NO_DEFAULT_PLUGINS") != NULL);
  EXPECT_FAIL(occseg_map_read(&m, bt), OCCSEG_EUNSUPPORTED, "no reader for extension '.bt'",
              "OCCSEG_NO_DEFAULT_PLUGINS is set", "occseg_plugins_load_default()");
  CHECK(m == NULL && occseg_plugin_count() == before && find_plugin("octomap_reader") < 0);
  CHECK(occseg_plugins_load_default(NULL) == OCCSEG_OK);
  CHECK(occseg_map_read(&m, bt) == OCCSEG_OK);
  occseg_map_free(m);
}

/* Writes `m` to `path` and reads it back: true when the values come back as they were. */
static int round_trip(const occseg_map *m, const char *path) {
  static float a[32 * 32 * 32], b[32 * 32 * 32];
  occseg_map *back = NULL;
  int same;
  remove(path);
  CHECK(occseg_map_write(m, path) == OCCSEG_OK);
  CHECK(occseg_map_read(&back, path) == OCCSEG_OK);
  same = back && occseg_map_values(m, a, 32 * 32 * 32) == OCCSEG_OK &&
         occseg_map_values(back, b, 32 * 32 * 32) == OCCSEG_OK && memcmp(a, b, sizeof a) == 0;
  occseg_map_free(back);
  return same;
}

/* The built-in readers and writers are registered by the library's first use of them, not by a
 * static initializer (capi/builtin_io.hpp): in this fresh process the first call that touches the
 * registry writes a .npy, and .npy and .nrrd then round-trip. Nothing else is loaded
 * (OCCSEG_NO_DEFAULT_PLUGINS=1), so the two built-in plugins are all there is. */
static void first_write(const char *work) {
  occseg_map *m = cube_map(0); /* occseg_map_from_buffer: no registry */
  char path[4096];
  CHECK(getenv("OCCSEG_NO_DEFAULT_PLUGINS") != NULL);
  snprintf(path, sizeof path, "%s/first.npy", work);
  CHECK(round_trip(m, path));
  snprintf(path, sizeof path, "%s/first.nrrd", work);
  CHECK(round_trip(m, path));
  CHECK(occseg_plugin_count() == 2 && find_plugin("builtin") == 0 && find_plugin("builtin_io") == 1);
  CHECK(find_stage(OCCSEG_STAGE_READER, ".yaml", "builtin_io") && find_stage(OCCSEG_STAGE_WRITER, ".npy", "builtin_io"));
  occseg_map_free(m);
}

/* A process whose first call loads a plugin: the built-in readers and writers are registered
 * before it, so they keep their place after "builtin" and the plugin comes third. */
static void first_load(const char *so) {
  CHECK(occseg_plugins_load(so) == OCCSEG_OK);
  CHECK(find_plugin("builtin") == 0 && find_plugin("builtin_io") == 1 && find_plugin("example") == 2);
  CHECK(find_stage(OCCSEG_STAGE_READER, ".npy", "builtin_io") && find_stage(OCCSEG_STAGE_READER, ".occtxt", "example"));
}

int main(int argc, char **argv) {
  if (argc == 4 && strcmp(argv[1], "example") == 0) example(argv[2], argv[3]);
  else if (argc == 3 && strcmp(argv[1], "errors") == 0) errors(argv[2]);
  else if (argc == 2 && strcmp(argv[1], "default") == 0) default_path();
  else if (argc == 2 && strcmp(argv[1], "default_broken") == 0) default_broken();
  else if (argc == 3 && strcmp(argv[1], "octomap") == 0) octomap(argv[2]);
  else if (argc == 3 && strcmp(argv[1], "pcd") == 0) pcd(argv[2]);
  else if (argc == 4 && strcmp(argv[1], "auto") == 0) auto_load(argv[2], argv[3]);
  else if (argc == 3 && strcmp(argv[1], "auto_off") == 0) auto_off(argv[2]);
  else if (argc == 3 && strcmp(argv[1], "first_write") == 0) first_write(argv[2]);
  else if (argc == 3 && strcmp(argv[1], "first_load") == 0) first_load(argv[2]);
  else {
    fprintf(stderr, "usage: test_plugins example SO WORKDIR | errors DIR | default | octomap FILE.bt\n");
    return 2;
  }
  if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
  else printf("all checks passed\n");
  return failures ? 1 : 0;
}
