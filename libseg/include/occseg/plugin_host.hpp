// The plugin host's entry for plugins compiled into a program (the C ABI's built-in .npy/.nrrd
// readers and writers): part of the plugin host, the one place of the core that sees the C plugin
// ABI. Everything else in the core uses the C++ entries of occseg/registry.hpp.
#pragma once
#include "occseg/grid.hpp"
#include "occseg/occseg_plugin.h"

namespace occseg {

// Registers a plugin compiled into the program through the same checks and host table as a
// loaded one. Throws Error(plugin) like load_plugin.
void register_static_plugin(const occseg_plugin_descriptor* descriptor);

// For readers compiled into the program only: hands a whole grid to the reader's sink, as
// map_alloc + filling its buffer would, without the second map and the copy (the grid is moved).
// The values are checked after the reader returns, as for every reader.
void deliver_grid(occseg_plugin_map_sink* sink, Grid&& grid);

}  // namespace occseg
