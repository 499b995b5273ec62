/* Exports a misspelt entry point: the host finds no occseg_plugin_entry. */
#include "common.h"
static int reg(const occseg_plugin_host *h, occseg_plugin_registrar *r) { (void)h; (void)r; return 0; }
DESCRIPTOR(d, OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, "no_entry", reg);
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entri(void) { return &d; }
