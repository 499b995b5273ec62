// The built-in map readers and writers (.npy, .nrrd; map_server .yaml read only): the plugin
// "builtin_io", registered explicitly by whoever uses the registry's files and plugins (no static
// initializer, which a linker drops from a static library when nothing refers to the object).
#pragma once

namespace occseg::capi {

// Registers the plugin "builtin_io" once per process; later calls return at once. Threads racing
// to the first call wait for the one that registers (std::call_once). The callers: every C
// function of plugins.cpp that reads or extends the registry's plugins, readers or writers, and
// the occseg command before it loads plugins. So "builtin_io" is always the plugin after
// "builtin", and owns .npy/.nrrd/.yaml before any loaded plugin could claim them.
// Throws Error(plugin) or std::bad_alloc when it fails; the next call then tries again.
void register_builtin_io();

}  // namespace occseg::capi
