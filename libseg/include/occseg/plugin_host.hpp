// The plugin host's entry for plugins compiled into a program (the C ABI's built-in .npy/.nrrd
// readers and writers): part of the plugin host, the one place of the core that sees the C plugin
// ABI. Everything else in the core uses the C++ entries of occseg/registry.hpp.
#pragma once
#include "occseg/occseg_plugin.h"

namespace occseg {

// Registers a plugin compiled into the program through the same checks and host table as a
// loaded one. Throws Error(plugin) like load_plugin.
void register_static_plugin(const occseg_plugin_descriptor* descriptor);

}  // namespace occseg
