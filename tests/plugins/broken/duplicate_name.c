/* Calls itself "builtin", the name of the plugin holding the built-in stages. */
#include "common.h"
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) { (void)h; (void)r; return 0; }
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, "builtin", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &d; }
