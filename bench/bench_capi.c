/* Helper of bench/compare: the C ABI as a program uses it, timed in-process.
 *   occseg_bench_capi RAW NX NY NZ PRESET THREADS REPEATS view|copy [f32|f64|u8|u16]
 * RAW holds nx * ny * nz float32 probabilities, x fastest (numpy's tofile of a C-order [z, y, x]
 * array). Each timed call makes the map (view: occseg_map_view_buffer, no copy; copy:
 * occseg_map_from_buffer), segments it (occseg_segment) and reads the labels (view:
 * occseg_result_labels_view; copy: occseg_result_labels into the program's array). Prints one
 * JSON line: best and median seconds, the stages' seconds of the best call and their sum, the
 * peak memory beyond the program's buffers (first and second call, larger reported), a checksum of
 * the labels. The last argument (default f32) is the dtype of the program's buffer: the floats of
 * RAW converted to it before anything is measured (u8/u16: round(p * max)), so the peak beyond
 * the program's buffers shows what a borrowed map of that dtype costs. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <occseg/occseg.h>

static long status_kb(const char *field) {
  FILE *f = fopen("/proc/self/status", "r");
  char line[256];
  long v = -1;
  const size_t n = strlen(field);
  if (!f) return -1;
  while (fgets(line, sizeof line, f))
    if (strncmp(line, field, n) == 0) v = strtol(line + n, NULL, 10);
  fclose(f);
  return v;
}

static void reset_peak(void) {
  FILE *f = fopen("/proc/self/clear_refs", "w");
  if (f) {
    fputs("5", f);
    fclose(f);
  }
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

int main(int argc, char **argv) {
  size_t dims[3], n, i;
  float *p;
  uint32_t *copy_out = NULL;
  FILE *f;
  occseg_params *params = NULL;
  int repeats, view, r, call, k;
  long rss0, peak[2];
  double *totals, best = 1e300, stages[8] = {0}, stage_sum = 0;
  const char *names[8] = {0};
  uint32_t nstages = 0, segments = 0;
  uint64_t checksum = 1469598103934665603ull;
  occseg_dtype dtype = OCCSEG_F32;
  void *buffer;
  if ((argc != 9 && argc != 10) || (strcmp(argv[8], "view") && strcmp(argv[8], "copy"))) {
    fprintf(stderr, "usage: occseg_bench_capi RAW NX NY NZ PRESET THREADS REPEATS view|copy [f32|f64|u8|u16]\n");
    return 1;
  }
  if (argc == 10) {
    if (strcmp(argv[9], "f64") == 0) dtype = OCCSEG_F64;
    else if (strcmp(argv[9], "u8") == 0) dtype = OCCSEG_U8;
    else if (strcmp(argv[9], "u16") == 0) dtype = OCCSEG_U16;
    else if (strcmp(argv[9], "f32") != 0) {
      fprintf(stderr, "occseg_bench_capi: dtype '%s' is not f32, f64, u8 or u16\n", argv[9]);
      return 1;
    }
  }
  for (k = 0; k < 3; ++k) dims[k] = (size_t)strtoull(argv[2 + k], NULL, 10);
  n = dims[0] * dims[1] * dims[2];
  repeats = atoi(argv[7]) > 0 ? atoi(argv[7]) : 1;
  view = strcmp(argv[8], "view") == 0;
  p = malloc(n * sizeof *p);
  totals = malloc((size_t)repeats * sizeof *totals);
  if (!view) copy_out = malloc(n * sizeof *copy_out);
  f = fopen(argv[1], "rb");
  if (!p || !totals || (!view && !copy_out) || !f || fread(p, sizeof *p, n, f) != n) {
    fprintf(stderr, "occseg_bench_capi: cannot read %zu floats from %s\n", n, argv[1]);
    return 1;
  }
  fclose(f);
  buffer = p;
  if (dtype != OCCSEG_F32) { /* the program's buffer in its dtype; the floats are freed */
    const size_t size = dtype == OCCSEG_F64 ? 8 : dtype == OCCSEG_U16 ? 2 : 1;
    buffer = malloc(n * size);
    if (!buffer) {
      fprintf(stderr, "occseg_bench_capi: out of memory\n");
      return 1;
    }
    for (i = 0; i < n; ++i) {
      if (dtype == OCCSEG_F64) ((double *)buffer)[i] = p[i];
      else if (dtype == OCCSEG_U16) ((uint16_t *)buffer)[i] = (uint16_t)(p[i] * 65535.0 + 0.5);
      else ((uint8_t *)buffer)[i] = (uint8_t)(p[i] * 255.0 + 0.5);
    }
    free(p);
    p = NULL;
  }
  if (!view) memset(copy_out, 0, n * sizeof *copy_out); /* the program's own array: paged in */
  if (occseg_params_create(&params) || occseg_params_set(params, "preset", argv[5]) ||
      occseg_params_set(params, "threads", argv[6])) {
    fprintf(stderr, "occseg_bench_capi: %s\n", occseg_last_error());
    return 1;
  }
  reset_peak();
  rss0 = status_kb("VmRSS:");
  for (call = -2; call < repeats; ++call) { /* two untimed calls measure the peak */
    occseg_map *map = NULL;
    occseg_result *res = NULL;
    const uint32_t *labels = NULL;
    size_t count = 0;
    const double t0 = now();
    int rc = view ? occseg_map_view_buffer(&map, buffer, dtype, dims, NULL, 1.0, 0)
                  : occseg_map_from_buffer(&map, buffer, dtype, dims, NULL, 1.0);
    if (rc == 0) rc = occseg_segment(&res, map, params);
    if (rc == 0 && view) rc = occseg_result_labels_view(res, &labels, &count);
    if (rc == 0 && !view) rc = occseg_result_labels(res, copy_out, n);
    const double s = now() - t0;
    if (rc != 0) {
      fprintf(stderr, "occseg_bench_capi: %s\n", occseg_last_error());
      return 1;
    }
    if (call < 0) {
      peak[call + 2] = status_kb("VmHWM:");
    } else {
      totals[call] = s;
      if (s < best) {
        uint32_t j;
        best = s;
        nstages = occseg_result_stage_count(res);
        if (nstages > 8) nstages = 8;
        stage_sum = 0;
        for (j = 0; j < nstages; ++j) {
          occseg_result_stage(res, j, &names[j], &stages[j]);
          stage_sum += stages[j];
        }
        names[nstages] = NULL;
        segments = occseg_result_segment_count(res);
        checksum = 1469598103934665603ull;
        if (!view) labels = copy_out;
        for (i = 0; i < n; ++i) checksum = (checksum ^ labels[i]) * 1099511628211ull;
      }
    }
    occseg_result_free(res);
    occseg_map_free(map);
    if (call < 0) reset_peak();
  }
  qsort(totals, (size_t)repeats, sizeof *totals, cmp);
  printf("{\"voxels\": %zu, \"best_s\": %.6f, \"median_s\": %.6f, \"stages_sum_s\": %.6f, \"segments\": %u, "
         "\"labels_fnv1a\": \"%016llx\", \"peak_extra_bytes_per_voxel\": %.3f, \"first_and_second_call\": [%.3f, %.3f], "
         "\"stages\": {",
         n, best, totals[repeats / 2], stage_sum, (unsigned)segments, (unsigned long long)checksum,
         ((peak[0] > peak[1] ? peak[0] : peak[1]) - rss0) * 1024.0 / (double)n, (peak[0] - rss0) * 1024.0 / (double)n,
         (peak[1] - rss0) * 1024.0 / (double)n);
  for (r = 0; r < (int)nstages; ++r) printf("%s\"%s\": %.6f", r ? ", " : "", names[r], stages[r]);
  printf("}}\n");
  occseg_params_free(params);
  free(buffer);
  free(totals);
  free(copy_out);
  return 0;
}
