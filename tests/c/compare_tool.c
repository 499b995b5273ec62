/* Segments one map twice through the C API and writes both results, for compare_cli.py:
 *   compare_tool MAP.npy OUT_NPY RAW.f64 NX NY NZ OUT_RAW
 * OUT_NPY: the map read with occseg_map_read. OUT_RAW: the same map as raw float64 in Fortran
 * order of [z, y, x] (x slowest), passed with strides to occseg_map_from_buffer. */
#include <stdio.h>
#include <stdlib.h>

#include <occseg/occseg.h>

static int fail(const char *what, int rc) {
  fprintf(stderr, "compare_tool: %s: %s: %s\n", what, occseg_status_name(rc), occseg_last_error());
  return 1;
}

static int segment_and_write(const occseg_map *map, const char *dir) {
  occseg_result *r = NULL;
  int rc = occseg_segment(&r, map, NULL);
  if (rc == 0) rc = occseg_result_write(r, dir);
  occseg_result_free(r);
  return rc;
}

int main(int argc, char **argv) {
  occseg_map *map = NULL;
  size_t dims[3], n;
  ptrdiff_t strides[3];
  double *raw;
  FILE *f;
  int rc;
  if (argc != 8) {
    fprintf(stderr, "usage: compare_tool MAP.npy OUT_NPY RAW.f64 NX NY NZ OUT_RAW\n");
    return 2;
  }
  if ((rc = occseg_map_read(&map, argv[1])) != 0) return fail("occseg_map_read", rc);
  rc = segment_and_write(map, argv[2]);
  occseg_map_free(map);
  if (rc != 0) return fail("npy map", rc);

  dims[0] = strtoul(argv[4], NULL, 10);
  dims[1] = strtoul(argv[5], NULL, 10);
  dims[2] = strtoul(argv[6], NULL, 10);
  n = dims[0] * dims[1] * dims[2];
  raw = malloc(n * sizeof *raw);
  f = fopen(argv[3], "rb");
  if (!raw || !f || fread(raw, sizeof *raw, n, f) != n) {
    fprintf(stderr, "compare_tool: cannot read %s\n", argv[3]);
    return 1;
  }
  fclose(f);
  strides[0] = (ptrdiff_t)(8 * dims[2] * dims[1]);
  strides[1] = (ptrdiff_t)(8 * dims[2]);
  strides[2] = 8;
  rc = occseg_map_from_buffer(&map, raw, OCCSEG_F64, dims, strides, 1.0);
  free(raw);
  if (rc != 0) return fail("occseg_map_from_buffer", rc);
  rc = segment_and_write(map, argv[7]);
  occseg_map_free(map);
  return rc == 0 ? 0 : fail("raw map", rc);
}
