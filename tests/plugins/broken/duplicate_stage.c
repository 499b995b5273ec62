/* Registers a fresh similarity and parameter, then the texture name "lbp6", which the built-in
 * plugin holds: the load must fail and take the fresh ones back. */
#include "common.h"
static double sim(const occseg_plugin_call *c, const uint32_t *a, const uint32_t *b, size_t n) {
  (void)c; (void)a; (void)b; (void)n; return 0;
}
static int64_t tex(const occseg_plugin_call *c, const occseg_plugin_grid *g, uint32_t bins, uint16_t *codes) {
  (void)c; (void)g; (void)bins; (void)codes; return 1;
}
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) {
  occseg_plugin_similarity s = {sizeof s, "dup_fresh_sim", "never visible", sim, 0};
  occseg_plugin_param p = {sizeof p, OCCSEG_PARAM_INT, "dup_fresh_param", "1", 0, 10, "never visible"};
  occseg_plugin_texture t = {sizeof t, "lbp6", "taken", tex, 0};
  int rc;
  if ((rc = h->register_similarity(r, &s)) != 0) return rc;
  if ((rc = h->declare_param(r, &p)) != 0) return rc;
  return h->register_texture(r, &t);
}
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, "duplicate_stage", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &d; }
