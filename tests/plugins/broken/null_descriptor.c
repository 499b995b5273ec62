/* The entry point returns NULL. */
#include "common.h"
OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor *occseg_plugin_entry(void) { return 0; }
