/* occseg_segment: the known scene, parameters, progress and cancel, threads, errors. */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <stdlib.h>

#include "suite.h"

enum { SCENE_N = SCENE_NX * SCENE_NY * SCENE_NZ };

static void check_segment(const occseg_result *r, uint32_t i, occseg_state st, uint64_t voxels, float p,
                          const uint32_t lo[3], const uint32_t hi[3], const double c[3]) {
  occseg_segment_info s;
  memset(&s, 0xAB, sizeof s);
  s.struct_size = sizeof s;
  assert_int_equal(occseg_result_segment(r, i, &s), OCCSEG_OK);
  assert_int_equal(s.struct_size, sizeof s);
  assert_int_equal(s.id, i);
  assert_int_equal(s.state, st);
  assert_int_equal(s.voxels, voxels);
  assert_true(s.mop > (double)p - 1e-6 && s.mop < (double)p + 1e-6);
  assert_memory_equal(s.bbox_min, lo, sizeof s.bbox_min);
  assert_memory_equal(s.bbox_max, hi, sizeof s.bbox_max);
  assert_true(s.centroid[0] > c[0] - 1e-9 && s.centroid[0] < c[0] + 1e-9);
  assert_true(s.centroid[1] > c[1] - 1e-9 && s.centroid[1] < c[1] + 1e-9);
  assert_true(s.centroid[2] > c[2] - 1e-9 && s.centroid[2] < c[2] + 1e-9);
}

static void scene_with_defaults(void **state) {
  occseg_map *m = scene_map();
  occseg_result *r = NULL;
  uint32_t *labels = malloc(SCENE_N * sizeof *labels);
  size_t dims[3], i, ones = 0;
  /* Hand-computed: ids follow the first voxel in x-fastest order; the free space surrounds both
   * boxes (10^3 and 20 x 15 x 15 voxels), centroids are the boxes' centres. */
  const uint32_t all_lo[3] = {0, 0, 0}, all_hi[3] = {55, 47, 39};
  const uint32_t b1_lo[3] = {5, 5, 5}, b1_hi[3] = {14, 14, 14}, b2_lo[3] = {30, 25, 20}, b2_hi[3] = {49, 39, 34};
  const double b1_c[3] = {9.5, 9.5, 9.5}, b2_c[3] = {39.5, 32, 27};
  double free_c[3];
  (void)state;
  assert_non_null(labels);
  /* Centroid of the free space: (sum over all voxels - sums over the boxes) / count. */
  free_c[0] = (27.5 * SCENE_N - 9.5 * 1000 - 39.5 * 4500) / 102020.0;
  free_c[1] = (23.5 * SCENE_N - 9.5 * 1000 - 32.0 * 4500) / 102020.0;
  free_c[2] = (19.5 * SCENE_N - 9.5 * 1000 - 27.0 * 4500) / 102020.0;
  assert_int_equal(occseg_segment(&r, m, NULL), OCCSEG_OK);
  assert_string_equal(occseg_last_error(), "");
  assert_int_equal(occseg_result_segment_count(r), 3);
  check_segment(r, 0, OCCSEG_FREE, SCENE_N - 1000 - 4500, 0.12f, all_lo, all_hi, free_c);
  check_segment(r, 1, OCCSEG_OCCUPIED, 1000, 0.97f, b1_lo, b1_hi, b1_c);
  check_segment(r, 2, OCCSEG_OCCUPIED, 4500, 0.97f, b2_lo, b2_hi, b2_c);
  assert_int_equal(occseg_result_dims(r, dims), OCCSEG_OK);
  assert_true(dims[0] == SCENE_NX && dims[1] == SCENE_NY && dims[2] == SCENE_NZ);
  assert_int_equal(occseg_result_labels(r, labels, SCENE_N), OCCSEG_OK);
  assert_int_equal(labels[0], 0);
  assert_int_equal(labels[7 + SCENE_NX * (7 + SCENE_NY * 7)], 1);
  assert_int_equal(labels[40 + SCENE_NX * (30 + SCENE_NY * 25)], 2);
  for (i = 0; i < SCENE_N; ++i) ones += labels[i] == 1;
  assert_int_equal(ones, 1000);
  free(labels);
  occseg_result_free(r);
  occseg_map_free(m);
}

struct progress_log {
  char text[512];
  int calls;
  const char *cancel_at; /* stage at which to return nonzero, or NULL */
};

static int on_progress(const char *stage, double fraction, void *user) {
  struct progress_log *log = user;
  size_t used = strlen(log->text);
  ++log->calls;
  if (fraction == 0.0 && used + strlen(stage) + 2 < sizeof log->text) {
    strcat(log->text, stage);
    strcat(log->text, " ");
  }
  return log->cancel_at && strcmp(stage, log->cancel_at) == 0;
}

static void progress_and_cancel(void **state) {
  occseg_map *m = scene_map();
  occseg_params *p = NULL;
  occseg_result *r = (occseg_result *)&r;
  struct progress_log log;
  (void)state;
  memset(&log, 0, sizeof log);
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set_progress(p, on_progress, &log), OCCSEG_OK);
  /* The callback survives a preset change. */
  assert_int_equal(occseg_params_preset(p, "paper"), OCCSEG_OK);
  assert_int_equal(occseg_segment(&r, m, p), OCCSEG_OK);
  assert_string_equal(log.text, "texture division creation refinement labelling ");
  assert_int_equal(log.calls, 10); /* start and end of five stages */
  occseg_result_free(r);

  memset(&log, 0, sizeof log);
  log.cancel_at = "creation";
  r = (occseg_result *)&r;
  EXPECT_FAIL(occseg_segment(&r, m, p), OCCSEG_ECANCELLED, "cancelled by the progress callback at stage 'creation'");
  assert_null(r);
  assert_string_equal(log.text, "texture division creation ");

  memset(&log, 0, sizeof log);
  assert_int_equal(occseg_params_set_progress(p, NULL, &log), OCCSEG_OK);
  assert_int_equal(occseg_segment(&r, m, p), OCCSEG_OK);
  assert_int_equal(log.calls, 0);
  occseg_result_free(r);
  occseg_params_free(p);
  occseg_map_free(m);
}

static void segment_errors(void **state) {
  occseg_map *m = scene_map();
  occseg_params *p = NULL;
  occseg_result *r = (occseg_result *)&r;
  (void)state;
  EXPECT_FAIL(occseg_segment(NULL, m, NULL), OCCSEG_EINVAL, "occseg_segment: argument 'out' is NULL");
  EXPECT_FAIL(occseg_segment(&r, NULL, NULL), OCCSEG_EINVAL, "argument 'map' is NULL");
  assert_null(r);
  assert_int_equal(occseg_params_create(&p), OCCSEG_OK);
  assert_int_equal(occseg_params_set_int(p, "smin", 128), OCCSEG_OK);
  r = (occseg_result *)&r;
  EXPECT_FAIL(occseg_segment(&r, m, p), OCCSEG_EINVAL, "smin': 128 is larger than smax = 64");
  assert_null(r);
  occseg_params_free(p);
  occseg_map_free(m);
}

/* Labels of the scene segmented with `threads` workers, from `map` read by several threads. */
struct job {
  const occseg_map *map;
  int threads;
  uint32_t *labels;
  int rc;
};

static void *run_job(void *arg) {
  struct job *j = arg;
  occseg_params *p = NULL;
  occseg_result *r = NULL;
  j->rc = occseg_params_create(&p);
  if (j->rc == 0) j->rc = occseg_params_set_int(p, "threads", j->threads);
  if (j->rc == 0) j->rc = occseg_segment(&r, j->map, p);
  if (j->rc == 0) j->rc = occseg_result_labels(r, j->labels, SCENE_N);
  occseg_result_free(r);
  occseg_params_free(p);
  return NULL;
}

static void threads_and_concurrency_do_not_change_results(void **state) {
  occseg_map *m = scene_map();
  struct job jobs[3];
  pthread_t t[3];
  int i;
  (void)state;
  for (i = 0; i < 3; ++i) {
    jobs[i].map = m;
    jobs[i].threads = i + 1;
    jobs[i].labels = malloc(SCENE_N * sizeof(uint32_t));
    assert_non_null(jobs[i].labels);
  }
  run_job(&jobs[0]); /* one worker, alone */
  for (i = 1; i < 3; ++i) assert_int_equal(pthread_create(&t[i], NULL, run_job, &jobs[i]), 0);
  for (i = 1; i < 3; ++i) assert_int_equal(pthread_join(t[i], NULL), 0);
  for (i = 0; i < 3; ++i) assert_int_equal(jobs[i].rc, OCCSEG_OK);
  assert_memory_equal(jobs[0].labels, jobs[1].labels, SCENE_N * sizeof(uint32_t));
  assert_memory_equal(jobs[0].labels, jobs[2].labels, SCENE_N * sizeof(uint32_t));
  for (i = 0; i < 3; ++i) free(jobs[i].labels);
  occseg_map_free(m);
}

static void uint8_scene_gives_the_same_labels(void **state) {
  /* The scene quantised to 8 bits (31/255 ~ 0.12, 247/255 ~ 0.97) keeps its structure. */
  float *f = scene_values();
  uint8_t *u = malloc(SCENE_N);
  uint32_t *a = malloc(SCENE_N * sizeof *a), *b = malloc(SCENE_N * sizeof *b);
  const size_t dims[3] = {SCENE_NX, SCENE_NY, SCENE_NZ};
  occseg_map *mf = scene_map(), *mu = NULL;
  occseg_result *rf = NULL, *ru = NULL;
  occseg_segment_info s;
  size_t i;
  (void)state;
  assert_true(f && u && a && b);
  for (i = 0; i < SCENE_N; ++i) u[i] = f[i] > 0.5f ? 247 : 31;
  assert_int_equal(occseg_map_from_buffer(&mu, u, OCCSEG_U8, dims, NULL, 0.1), OCCSEG_OK);
  assert_int_equal(occseg_segment(&rf, mf, NULL), OCCSEG_OK);
  assert_int_equal(occseg_segment(&ru, mu, NULL), OCCSEG_OK);
  assert_int_equal(occseg_result_labels(rf, a, SCENE_N), OCCSEG_OK);
  assert_int_equal(occseg_result_labels(ru, b, SCENE_N), OCCSEG_OK);
  assert_memory_equal(a, b, SCENE_N * sizeof *a);
  s.struct_size = sizeof s;
  assert_int_equal(occseg_result_segment(ru, 1, &s), OCCSEG_OK);
  assert_true(s.mop > (double)(float)(247 / 255.0) - 1e-9 && s.mop < (double)(float)(247 / 255.0) + 1e-9);
  occseg_result_free(rf);
  occseg_result_free(ru);
  occseg_map_free(mf);
  occseg_map_free(mu);
  free(f);
  free(u);
  free(a);
  free(b);
}

int run_segment_tests(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(scene_with_defaults),
      cmocka_unit_test(progress_and_cancel),
      cmocka_unit_test(segment_errors),
      cmocka_unit_test(threads_and_concurrency_do_not_change_results),
      cmocka_unit_test(uint8_scene_gives_the_same_labels),
  };
  return cmocka_run_group_tests_name("segment", tests, NULL, NULL);
}
