/*
 * An example occseg plugin, written as an outside author would: plain C99, the installed
 * occseg_plugin.h only, no link with liboccseg. It adds
 *   - texture operator "lbp6ri": the 6-neighbour LBP made invariant to the 24 rotations of the
 *     cube (10 pattern classes x b contrast levels), with its own parameter ri_flat_below;
 *   - similarity "l1": half the L1 distance between the normalised histograms (0 .. 1);
 *   - reader and writer ".occtxt": a small text format ("occtxt nx ny nz voxel ox oy oz" then
 *     the probabilities, x fastest).
 * Linux: the writer uses POSIX open/fsync and getrandom.
 */
#define _GNU_SOURCE /* getrandom, O_CLOEXEC, O_NOFOLLOW */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>

#include <occseg/occseg_plugin.h>

/* ---- lbp6ri ------------------------------------------------------------------------------- */

/* Class of a 6-bit pattern (bit 2a and 2a+1: the two neighbours along axis a) under rotations
 * of the cube: the number of set bits k, and for k = 2, 3, 4 whether set (k = 2, 3) or unset
 * (k = 4) neighbours face each other along an axis. Classes 0..9:
 *   0: k=0   1: k=1   2: k=2 adjacent   3: k=2 opposite   4: k=3 corner   5: k=3 line+1
 *   6: k=4 unset adjacent   7: k=4 unset opposite   8: k=5   9: k=6 */
static unsigned ri_class(unsigned p) {
  unsigned k = 0, full = 0, empty = 0, a;
  for (a = 0; a < 3; ++a) {
    const unsigned pair = (p >> (2 * a)) & 3u;
    k += (pair & 1u) + (pair >> 1);
    full += pair == 3u;
    empty += pair == 0u;
  }
  switch (k) {
    case 0: return 0;
    case 1: return 1;
    case 2: return full ? 3 : 2;
    case 3: return full ? 5 : 4;
    case 4: return empty ? 7 : 6;
    case 5: return 8;
    default: return 9;
  }
}

static int64_t lbp6ri_compute(const occseg_plugin_call *call, const occseg_plugin_grid *g, uint32_t bins,
                              uint16_t *codes) {
  const size_t nx = g->dims[0], ny = g->dims[1], nz = g->dims[2], n = nx * ny * nz;
  const ptrdiff_t off[6] = {-1, 1, -(ptrdiff_t)nx, (ptrdiff_t)nx, -(ptrdiff_t)(nx * ny), (ptrdiff_t)(nx * ny)};
  double flat_below = 0, *contrast;
  unsigned char *cls;
  size_t x, y, z, i;
  int rc;
  if (nx < 3 || ny < 3 || nz < 3) {
    call->host->set_error("lbp6ri needs a 3D map with at least 3 voxels along each axis");
    return OCCSEG_EDIMS;
  }
  if ((rc = call->host->param_get_double(call, "ri_flat_below", &flat_below)) != 0) return rc;
  contrast = (double *)malloc(n * sizeof *contrast);
  cls = (unsigned char *)calloc(n, 1);
  if (!contrast || !cls) {
    free(contrast);
    free(cls);
    call->host->set_error("lbp6ri: out of memory");
    return OCCSEG_ENOMEM;
  }
  for (i = 0; i < n; ++i) contrast[i] = NAN; /* outer faces: no texture */
  for (z = 1; z + 1 < nz; ++z)
    for (y = 1; y + 1 < ny; ++y)
      for (x = 1; x + 1 < nx; ++x) {
        const size_t c = x + nx * (y + ny * z);
        const double centre = g->values[c];
        double s1 = 0, s0 = 0;
        int n1 = 0, n0 = 0, k;
        unsigned p = 0;
        for (k = 0; k < 6; ++k) {
          const double v = g->values[(ptrdiff_t)c + off[k]];
          if (v >= centre) {
            p |= 1u << k;
            s1 += v;
            ++n1;
          } else {
            s0 += v;
            ++n0;
          }
        }
        cls[c] = (unsigned char)ri_class(p);
        contrast[c] = (n1 && n0) ? s1 / n1 - s0 / n0 : 0.0;
        if (contrast[c] < flat_below) contrast[c] = 0.0; /* weak contrasts count as flat */
      }
  rc = call->host->contrast_levels(contrast, n, bins, codes);
  if (rc == 0)
    for (i = 0; i < n; ++i)
      if (codes[i] != OCCSEG_NO_TEXTURE) codes[i] = (uint16_t)(cls[i] * bins + codes[i]);
  free(contrast);
  free(cls);
  return rc ? rc : (int64_t)(10 * bins);
}

/* ---- l1 ----------------------------------------------------------------------------------- */

static double l1_compare(const occseg_plugin_call *call, const uint32_t *a, const uint32_t *b, size_t bins) {
  double na = 0, nb = 0, d = 0;
  size_t i;
  (void)call;
  for (i = 0; i < bins; ++i) {
    na += a[i];
    nb += b[i];
  }
  if (na == 0 || nb == 0) return 0.0;
  for (i = 0; i < bins; ++i) d += fabs(a[i] / na - b[i] / nb);
  return d / 2 > 1e-12 ? d / 2 : 0.0;
}

/* ---- .occtxt ------------------------------------------------------------------------------ */

static int io_fail(const occseg_plugin_call *call, int code, const char *what, const char *path) {
  char msg[1024];
  snprintf(msg, sizeof msg, "'%s': %s", path, what);
  call->host->set_error(msg);
  return code;
}

static int occtxt_read(const occseg_plugin_call *call, const char *path, const char *const *options,
                       occseg_plugin_map_sink *sink) {
  size_t dims[3], i, n;
  double voxel = 1, origin[3];
  float *values = NULL;
  int rc;
  FILE *f;
  if (options && options[0]) return io_fail(call, OCCSEG_EINVAL, "the .occtxt reader takes no options", path);
  if (!(f = fopen(path, "r"))) return io_fail(call, OCCSEG_EIO, "cannot open", path);
  if (fscanf(f, "occtxt %zu %zu %zu %lf %lf %lf %lf", &dims[0], &dims[1], &dims[2], &voxel, &origin[0], &origin[1],
             &origin[2]) != 7) {
    fclose(f);
    return io_fail(call, OCCSEG_EFORMAT, "no 'occtxt nx ny nz voxel_size ox oy oz' header", path);
  }
  if ((rc = call->host->map_alloc(sink, dims, voxel, origin, &values)) != 0) {
    fclose(f);
    return rc; /* the host has set the error */
  }
  n = dims[0] * dims[1] * dims[2];
  for (i = 0; i < n; ++i)
    if (fscanf(f, "%f", &values[i]) != 1) {
      fclose(f);
      return io_fail(call, OCCSEG_EFORMAT, "fewer values than nx * ny * nz", path);
    }
  fclose(f);
  return 0;
}

/* A new temporary beside `path` (so the rename stays in one file system): a random name, created
 * with O_EXCL | O_NOFOLLOW, so a file or symbolic link planted under the name is never opened (a
 * predictable name in a shared folder would let a planted link redirect the write elsewhere),
 * and mode 0666 less the umask, like any new file. Returns the descriptor, or -1 with errno. */
static int create_temp(const char *path, char *tmp, size_t size) {
  int attempt;
  for (attempt = 0; attempt < 100; ++attempt) {
    unsigned long long r = 0;
    int fd;
    if (getrandom(&r, sizeof r, GRND_NONBLOCK) != (ssize_t)sizeof r)
      r ^= ((unsigned long long)getpid() << 32) ^ (unsigned long long)time(NULL) ^
           (unsigned long long)(attempt + 1) * 0x9E3779B97F4A7C15ull;
    if (snprintf(tmp, size, "%s.tmp-%016llx", path, r) >= (int)size) {
      errno = ENAMETOOLONG;
      return -1;
    }
    fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;
}

static int occtxt_write(const occseg_plugin_call *call, const char *path, const occseg_plugin_grid *g,
                        const char *const *options) {
  const size_t n = g->dims[0] * g->dims[1] * g->dims[2];
  char tmp[4096];
  size_t i;
  int ok, fd;
  FILE *f;
  if (options && options[0]) return io_fail(call, OCCSEG_EINVAL, "the .occtxt writer takes no options", path);
  if ((fd = create_temp(path, tmp, sizeof tmp)) < 0) return io_fail(call, OCCSEG_EIO, "cannot create a temporary", path);
  if (!(f = fdopen(fd, "w"))) {
    close(fd);
    remove(tmp);
    return io_fail(call, OCCSEG_EIO, "cannot create", path);
  }
  ok = fprintf(f, "occtxt %zu %zu %zu %.17g %.17g %.17g %.17g\n", g->dims[0], g->dims[1], g->dims[2],
               g->voxel_size, g->origin[0], g->origin[1], g->origin[2]) > 0;
  for (i = 0; ok && i < n; ++i) ok = fprintf(f, "%.9g\n", g->values[i]) > 0;
  ok = fflush(f) == 0 && fsync(fd) == 0 && ok; /* on disk before it replaces the old file */
  ok = (fclose(f) == 0) && ok;
  if (!ok || rename(tmp, path) != 0) { /* all or nothing */
    remove(tmp);
    return io_fail(call, OCCSEG_EIO, "cannot write", path);
  }
  return 0;
}

/* ---- registration ------------------------------------------------------------------------- */

static int register_example(const occseg_plugin_host *host, occseg_plugin_registrar *r) {
  occseg_plugin_texture tex = {sizeof tex, "lbp6ri",
                               "6-neighbour LBP/C invariant to cube rotations (10 classes x b codes), 3D maps",
                               lbp6ri_compute, NULL};
  occseg_plugin_similarity sim = {sizeof sim, "l1", "half the L1 distance of the normalised histograms (0..1)",
                                  l1_compare, NULL};
  occseg_plugin_reader rd = {sizeof rd, ".occtxt", "text map: header line, then probabilities x fastest",
                             occtxt_read, NULL};
  occseg_plugin_writer wr = {sizeof wr, ".occtxt", "text map: header line, then probabilities x fastest",
                             occtxt_write, NULL};
  occseg_plugin_param flat = {sizeof flat, OCCSEG_PARAM_DOUBLE, "ri_flat_below", "0", 0.0, 1.0,
                              "lbp6ri: contrasts below this count as flat (level 0)"};
  int rc;
  if (host->struct_size < sizeof *host) {
    host->set_error("the host table is older than this plugin's ABI");
    return OCCSEG_EPLUGIN;
  }
  if ((rc = host->register_texture(r, &tex)) != 0) return rc;
  if ((rc = host->register_similarity(r, &sim)) != 0) return rc;
  if ((rc = host->register_reader(r, &rd)) != 0) return rc;
  if ((rc = host->register_writer(r, &wr)) != 0) return rc;
  return host->declare_param(r, &flat);
}

static const occseg_plugin_descriptor descriptor = {
    OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof(occseg_plugin_descriptor),
    "example", "1.0.0", "example plugin: lbp6ri texture, l1 similarity, .occtxt maps", register_example};

OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &descriptor; }
