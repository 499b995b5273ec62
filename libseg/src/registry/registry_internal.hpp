// Shared by the plugin host (registry.cpp, plugin_loader.cpp, run_stages.cpp, builtin_stages.cpp) and params.cpp:
// the pieces of the registry that are not public API.
#pragma once
#include <cstdint>
#include <string>

#include "occseg/occseg_plugin.h"
#include "occseg/plugin_host.hpp"
#include "occseg/params.hpp"
#include "occseg/registry.hpp"

namespace occseg {

// Validates a descriptor, runs its register function with a fresh registrar and commits what it
// registered, all under the loading lock. `path` is "" for plugins compiled into the program.
// Throws Error(plugin) naming the plugin and the reason; then nothing was committed. Returns the
// plugin's name.
std::string install_descriptor(const occseg_plugin_descriptor* descriptor, const std::string& path, void* handle);

// True when a plugin of that name is registered.
bool plugin_loaded(const std::string& name);

// The table handed to every register function and callback.
const occseg_plugin_host& host_table();

// The calling thread's plugin error text (host->set_error).
void set_plugin_error(const std::string& message);
void clear_plugin_error();
std::string plugin_error();  // "(no message)" when none was set

// The C++ entries' callables around a plugin's C callbacks (run_stages.cpp): each sets up the
// call, turns the callback's failure into an Error naming the stage and its plugin, and checks
// what it returned.
std::function<TextureMap(const Grid&, const Params&)> plugin_texture(occseg_plugin_texture_fn fn, void* user,
                                                                     const std::string& name, const std::string& plugin);
std::function<double(const std::uint32_t*, const std::uint32_t*, std::size_t)> plugin_similarity(
    occseg_plugin_similarity_fn fn, void* user);
std::function<Grid(const std::string&, const std::vector<std::string>&)> plugin_reader(occseg_plugin_read_fn fn, void* user,
                                                                                        const std::string& plugin);
std::function<void(const std::string&, const Grid&, const std::vector<std::string>&)> plugin_writer(
    occseg_plugin_write_fn fn, void* user, const std::string& plugin);

// Host functions implemented in run_stages.cpp.
int host_param_get_int(const occseg_plugin_call* call, const char* name, int64_t* out);
int host_param_get_double(const occseg_plugin_call* call, const char* name, double* out);
int host_param_get_string(const occseg_plugin_call* call, const char* name, char* buf, size_t size);
int host_map_alloc(occseg_plugin_map_sink* sink, const size_t dims[3], double voxel_size, const double origin[3],
                   float** values);
int host_contrast_levels(const double* contrast, size_t count, uint32_t bins, uint16_t* levels);

// builtin_stages.cpp: the built-in stages as a plugin descriptor, and their C++ fast paths,
// attached after the descriptor is installed.
const occseg_plugin_descriptor* builtin_stages_descriptor();
void attach_builtin_natives();
void set_native_texture(const std::string& name, TextureMap (*native)(const Grid&, const Params&),
                        int (*native_into)(const Grid&, const Params&, const kernels::Table&, std::uint16_t*,
                                           std::uint8_t*, const detail::MapRowSink*) = nullptr);

// params.cpp: parses `text` as a value of the parameter `info` (number kinds: a finite number
// within the bounds, integral for "int"); throws Error(invalid_argument) naming it otherwise.
double check_param_value(const ParamInfo& info, const std::string& text);

}  // namespace occseg
