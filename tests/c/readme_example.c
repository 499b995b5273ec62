/* Segments a small map with the occseg C API and prints the segment table.
 * Build: cc -std=c99 example.c $(pkg-config --cflags --libs occseg) */
#include <stdio.h>

#include <occseg/occseg.h>

enum { N = 32 }; /* a 32 x 32 x 32 map */

static int report(const char *stage, double fraction, void *user) {
  (void)user;
  if (fraction == 0.0) printf("stage: %s\n", stage);
  return 0; /* nonzero would cancel */
}

int main(void) {
  static float p[N * N * N];
  const size_t dims[3] = {N, N, N};
  occseg_map *map = NULL;
  occseg_params *params = NULL;
  occseg_result *result = NULL;
  uint32_t i, count;
  int x, y, z, rc;

  /* Free space (p = 0.1) holding an occupied 8 x 8 x 8 box (p = 0.9), x fastest. */
  for (z = 0; z < N; ++z)
    for (y = 0; y < N; ++y)
      for (x = 0; x < N; ++x) {
        const int inside = x >= 12 && x < 20 && y >= 12 && y < 20 && z >= 12 && z < 20;
        p[x + N * (y + N * z)] = inside ? 0.9f : 0.1f;
      }

  rc = occseg_map_from_buffer(&map, p, OCCSEG_F32, dims, NULL, 0.05 /* metres */);
  if (rc == 0) rc = occseg_params_create(&params);
  if (rc == 0) rc = occseg_params_set(params, "preset", "default");
  if (rc == 0) rc = occseg_params_set_int(params, "threads", 2);
  if (rc == 0) rc = occseg_params_set_progress(params, report, NULL);
  if (rc == 0) rc = occseg_segment(&result, map, params);
  if (rc != 0) {
    fprintf(stderr, "occseg %s: %s: %s\n", occseg_version_string(), occseg_status_name(rc), occseg_last_error());
  } else {
    count = occseg_result_segment_count(result);
    for (i = 0; i < count; ++i) {
      occseg_segment_info s;
      s.struct_size = sizeof s; /* always, before each call */
      occseg_result_segment(result, i, &s);
      printf("segment %u: %s, %llu voxels, mop %.2f, bbox (%u, %u, %u)-(%u, %u, %u)\n", (unsigned)s.id,
             s.state == OCCSEG_FREE ? "free" : s.state == OCCSEG_OCCUPIED ? "occupied" : "unknown",
             (unsigned long long)s.voxels, s.mop, (unsigned)s.bbox_min[0], (unsigned)s.bbox_min[1],
             (unsigned)s.bbox_min[2], (unsigned)s.bbox_max[0], (unsigned)s.bbox_max[1], (unsigned)s.bbox_max[2]);
    }
  }
  occseg_result_free(result); /* all NULL-safe */
  occseg_params_free(params);
  occseg_map_free(map);
  return rc == 0 ? 0 : 1;
}
