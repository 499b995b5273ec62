/* Registers a texture and a parameter, then its register function reports a failure. */
#include "common.h"
static int64_t tex(const occseg_plugin_call *c, const occseg_plugin_grid *g, uint32_t bins, uint16_t *codes) {
  (void)c; (void)g; (void)bins; (void)codes; return 1;
}
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) {
  occseg_plugin_texture t = {sizeof t, "fails_tex", "never visible", tex, 0};
  occseg_plugin_param p = {sizeof p, OCCSEG_PARAM_DOUBLE, "fails_param", "0.5", 0, 1, "never visible"};
  int rc;
  if ((rc = h->register_texture(r, &t)) != 0) return rc;
  if ((rc = h->declare_param(r, &p)) != 0) return rc;
  h->set_error("deliberate failure: the licence file is missing");
  return OCCSEG_EINVAL;
}
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, "register_fails", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &d; }
