/* occseg_context_*: a caller-owned thread pool; results identical to occseg_segment(). */
#include <stdlib.h>

#include "suite.h"

enum { N = SCENE_NX * SCENE_NY * SCENE_NZ };

static void lifecycle_and_errors(void **state) {
  occseg_context *c = (occseg_context *)&c;
  (void)state;
  assert_int_equal(occseg_context_new(&c, 3), OCCSEG_OK);
  assert_non_null(c);
  /* Three in all, unless the system refused a worker (then fewer, never more). */
  assert_true(occseg_context_threads(c) >= 1 && occseg_context_threads(c) <= 3);
  occseg_context_free(c);
  assert_int_equal(occseg_context_new(&c, 0), OCCSEG_OK); /* one per core */
  assert_true(occseg_context_threads(c) >= 1);
  occseg_context_free(c);
  c = (occseg_context *)&c;
  EXPECT_FAIL(occseg_context_new(&c, -1), OCCSEG_EINVAL, "occseg_context_new: threads = -1 is outside [0, 1024]");
  assert_null(c);
  EXPECT_FAIL(occseg_context_new(&c, 1025), OCCSEG_EINVAL, "threads = 1025");
  EXPECT_FAIL(occseg_context_new(NULL, 1), OCCSEG_EINVAL, "argument 'out' is NULL");
  assert_int_equal(occseg_context_threads(NULL), 0);
  occseg_context_free(NULL);
}

static uint32_t *labels_of(const occseg_result *r) {
  uint32_t *l = malloc(N * sizeof *l);
  assert_non_null(l);
  assert_int_equal(occseg_result_labels(r, l, N), OCCSEG_OK);
  return l;
}

static int count_calls(const char *stage, double fraction, void *user) {
  (void)stage;
  (void)fraction;
  ++*(int *)user;
  return 0;
}

static void results_equal_plain_segment(void **state) {
  occseg_map *m = scene_map();
  occseg_params *p = NULL;
  occseg_result *plain = NULL, *r = NULL;
  uint32_t *want, *got;
  int threads, rep, calls = 0;
  (void)state;
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set_progress(p, count_calls, &calls), OCCSEG_OK);
  assert_int_equal(occseg_segment(&plain, m, p), OCCSEG_OK);
  want = labels_of(plain);
  for (threads = 1; threads <= 3; ++threads) {
    occseg_context *c = NULL;
    assert_int_equal(occseg_context_new(&c, threads), OCCSEG_OK);
    for (rep = 0; rep < 2; ++rep) { /* the pool is reused across calls */
      calls = 0;
      assert_int_equal(occseg_context_segment(&r, c, m, p), OCCSEG_OK);
      assert_int_equal(calls, 10); /* start and end of five stages, on this thread */
      assert_int_equal(occseg_result_segment_count(r), occseg_result_segment_count(plain));
      got = labels_of(r);
      assert_memory_equal(got, want, N * sizeof *got);
      free(got);
      occseg_result_free(r);
      r = NULL;
    }
    occseg_context_free(c);
  }
  free(want);
  occseg_result_free(plain);
  occseg_params_free(p);
  occseg_map_free(m);
}

static void segment_errors(void **state) {
  occseg_map *m = scene_map();
  occseg_context *c = NULL;
  occseg_result *r = (occseg_result *)&r;
  (void)state;
  assert_int_equal(occseg_context_new(&c, 2), OCCSEG_OK);
  EXPECT_FAIL(occseg_context_segment(&r, NULL, m, NULL), OCCSEG_EINVAL, "occseg_context_segment: argument 'context' is NULL");
  assert_null(r);
  r = (occseg_result *)&r;
  EXPECT_FAIL(occseg_context_segment(&r, c, NULL, NULL), OCCSEG_EINVAL, "argument 'map' is NULL");
  assert_null(r);
  EXPECT_FAIL(occseg_context_segment(NULL, c, m, NULL), OCCSEG_EINVAL, "argument 'out' is NULL");
  /* The context is still usable after failures. */
  assert_int_equal(occseg_context_segment(&r, c, m, NULL), OCCSEG_OK);
  assert_int_equal(occseg_result_segment_count(r), 3);
  occseg_result_free(r);
  occseg_context_free(c);
  occseg_map_free(m);
}

/* An nx x ny x nz map with every voxel at `p`. */
static occseg_map *uniform_map(size_t nx, size_t ny, size_t nz, float p) {
  const size_t dims[3] = {nx, ny, nz};
  float *v = malloc(nx * ny * nz * sizeof *v);
  occseg_map *m = NULL;
  size_t i;
  assert_non_null(v);
  for (i = 0; i < nx * ny * nz; ++i) v[i] = p;
  assert_int_equal(occseg_map_from_buffer(&m, v, OCCSEG_F32, dims, NULL, 1.0), OCCSEG_OK);
  free(v);
  return m;
}

/* A recycled label array is written over completely: after the scene's labels (585 segments'
 * worth of ids), a uniform free map of the same size must come out all 0; then the scene again
 * equals the plain call; a smaller and a larger map after a recycle are right too. */
static void recycled_labels_are_rewritten(void **state) {
  occseg_map *scene = scene_map(), *flat = uniform_map(SCENE_NX, SCENE_NY, SCENE_NZ, 0.1f);
  occseg_map *small = uniform_map(7, 5, 3, 0.9f), *big = uniform_map(SCENE_NX, SCENE_NY, SCENE_NZ + 3, 0.1f);
  occseg_context *c = NULL;
  occseg_result *plain = NULL, *r = NULL;
  uint32_t *want, *got, zero[7 * 5 * 3] = {0};
  size_t i;
  (void)state;
  assert_int_equal(occseg_segment(&plain, scene, NULL), OCCSEG_OK);
  want = labels_of(plain);
  assert_int_equal(occseg_context_new(&c, 2), OCCSEG_OK);
  assert_int_equal(occseg_context_segment(&r, c, scene, NULL), OCCSEG_OK);
  occseg_context_recycle(c, r);
  assert_int_equal(occseg_context_segment(&r, c, flat, NULL), OCCSEG_OK);
  assert_int_equal(occseg_result_segment_count(r), 1);
  got = labels_of(r);
  for (i = 0; i < N; ++i) assert_int_equal(got[i], 0);
  free(got);
  occseg_context_recycle(c, r);
  assert_int_equal(occseg_context_segment(&r, c, scene, NULL), OCCSEG_OK);
  got = labels_of(r);
  assert_memory_equal(got, want, N * sizeof *got);
  free(got);
  occseg_context_recycle(c, r);
  assert_int_equal(occseg_context_segment(&r, c, small, NULL), OCCSEG_OK); /* fewer voxels */
  {
    uint32_t l[7 * 5 * 3];
    assert_int_equal(occseg_result_labels(r, l, 7 * 5 * 3), OCCSEG_OK);
    assert_memory_equal(l, zero, sizeof l);
  }
  occseg_context_recycle(c, r);
  assert_int_equal(occseg_context_segment(&r, c, big, NULL), OCCSEG_OK); /* more than it holds */
  assert_int_equal(occseg_result_segment_count(r), 1);
  occseg_context_recycle(c, r);
  occseg_context_recycle(c, NULL); /* no-op */
  assert_int_equal(occseg_context_segment(&r, c, scene, NULL), OCCSEG_OK);
  occseg_context_recycle(NULL, r); /* just frees it */
  occseg_context_free(c);          /* frees the array it holds */
  free(want);
  occseg_result_free(plain);
  occseg_map_free(scene);
  occseg_map_free(flat);
  occseg_map_free(small);
  occseg_map_free(big);
}

int run_context_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(lifecycle_and_errors),
      cmocka_unit_test(results_equal_plain_segment),
      cmocka_unit_test(segment_errors),
      cmocka_unit_test(recycled_labels_are_rewritten),
  };
  return cmocka_run_group_tests_name("context", tests, NULL, NULL);
}
