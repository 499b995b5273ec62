/*
 * The child process of OutOfMemory.SegmentReportsEnomemAtEveryLimitAndSucceedsWithEnough
 * (test_oom.cpp): a fresh program, not a fork of the test binary. A fork inherits the memory the
 * earlier tests of that process left behind: glibc hands the malloc arenas of the parent's
 * threads, with their reserved address space, to the child's new threads, so the call's worker
 * threads would grow into address space already counted as in use, and no limit would bite.
 *
 * Usage: occseg_oom_child HEADROOM_BYTES
 * Makes a 96^3 map (0.1 with a 0.9 box of half the size), then limits the address space
 * (RLIMIT_AS) to what is in use plus HEADROOM_BYTES and segments with 2 threads.
 * Exit 0: OK; 1: OCCSEG_ENOMEM with its message and no result; 2 and up: anything else.
 */
#define _POSIX_C_SOURCE 200809L /* sysconf */
#include <occseg/occseg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

/* Bytes of address space this process uses now. */
static size_t address_space(void) {
  FILE *f = fopen("/proc/self/statm", "r");
  unsigned long pages = 0;
  if (!f || fscanf(f, "%lu", &pages) != 1) pages = 0;
  if (f) fclose(f);
  return pages * (size_t)sysconf(_SC_PAGESIZE);
}

int main(int argc, char **argv) {
  enum { n = 96 };
  const size_t d[3] = {n, n, n};
  size_t x, y, z, limit;
  float *p;
  occseg_map *m = NULL;
  occseg_params *params = NULL;
  occseg_result *res = NULL;
  struct rlimit r;
  char *end = NULL;
  unsigned long long headroom;
  int rc;
  if (argc != 2) return 2;
  headroom = strtoull(argv[1], &end, 10);
  if (end == argv[1] || *end) return 2;
  p = (float *)malloc((size_t)n * n * n * sizeof *p);
  if (!p) return 3;
  for (z = 0; z < n; ++z)
    for (y = 0; y < n; ++y)
      for (x = 0; x < n; ++x) {
        const int in = x >= n / 4 && x < 3 * n / 4 && y >= n / 4 && y < 3 * n / 4 && z >= n / 4 && z < 3 * n / 4;
        p[x + n * (y + n * z)] = in ? 0.9f : 0.1f;
      }
  if (occseg_map_from_buffer(&m, p, OCCSEG_F32, d, NULL, 1.0) || occseg_params_create(&params) ||
      occseg_params_set_int(params, "threads", 2))
    return 5;
  limit = address_space() + (size_t)headroom;
  r.rlim_cur = r.rlim_max = limit;
  if (setrlimit(RLIMIT_AS, &r) != 0) return 6;
  rc = occseg_segment(&res, m, params);
  if (rc == OCCSEG_OK) return res ? 0 : 7;
  if (rc == OCCSEG_ENOMEM && !res && strstr(occseg_last_error(), "occseg_segment: out of memory")) return 1;
  fprintf(stderr, "status %d: %s\n", rc, occseg_last_error());
  return 8;
}
