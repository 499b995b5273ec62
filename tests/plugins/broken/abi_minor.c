/* Built for a newer minor than the host's: it may use host functions the host lacks. */
#include "common.h"
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) { (void)h; (void)r; return 0; }
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR + 1, "abi_minor", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return &d; }
