/* Built for the next plugin ABI major: incompatible. */
#include "common.h"
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) { (void)h; (void)r; return 0; }
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR + 1, 0, "abi_major", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &d; }
