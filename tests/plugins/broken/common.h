/* Deliberately broken plugins for tests/plugins: each file is one way a plugin can be wrong. */
#include <math.h>
#include <occseg/occseg_plugin.h>

#define DESCRIPTOR(var, major, minor, name, fn) \
  static const occseg_plugin_descriptor var = {major, minor, sizeof(occseg_plugin_descriptor), name, "0.0.1", \
                                               "deliberately broken (tests/plugins)", fn}
