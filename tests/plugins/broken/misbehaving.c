/* Loads fine, but its stages misbehave when run: a texture operator writing a code beyond the
 * count it returns, a similarity returning NaN, a reader returning success without a map. */
#include "common.h"
static int64_t tex(const occseg_plugin_call *c, const occseg_plugin_grid *g, uint32_t bins, uint16_t *codes) {
  const size_t n = g->dims[0] * g->dims[1] * g->dims[2];
  size_t i;
  (void)c; (void)bins;
  for (i = 0; i < n; ++i) codes[i] = (uint16_t)(i == 5 ? 7 : 0);
  return 5; /* code 7 at voxel 5 is out of [0, 5) */
}
static double sim(const occseg_plugin_call *c, const uint32_t *a, const uint32_t *b, size_t n) {
  (void)c; (void)a; (void)b; (void)n; return NAN;
}
static int rd(const occseg_plugin_call *c, const char *path, const char *const *o, occseg_plugin_map_sink *s) {
  (void)c; (void)path; (void)o; (void)s; return 0;
}
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) {
  occseg_plugin_texture t = {sizeof t, "bad_codes", "writes an out-of-range code", tex, 0};
  occseg_plugin_similarity s = {sizeof s, "nan_sim", "returns NaN", sim, 0};
  occseg_plugin_reader rr = {sizeof rr, ".nomap", "returns no map", rd, 0};
  int rc;
  if ((rc = h->register_texture(r, &t)) != 0) return rc;
  if ((rc = h->register_similarity(r, &s)) != 0) return rc;
  return h->register_reader(r, &rr);
}
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, "misbehaving", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &d; }
