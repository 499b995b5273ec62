// The process-wide registry of pipeline stages (texture operators, histogram similarities), map
// readers and writers, and plugin-declared parameters, filled by the built-in stages and by
// plugins through one interface. The entries are C++: the plugin host (libseg/src/registry/, the
// only part of the core that sees the C plugin ABI, occseg/occseg_plugin.h) wraps a plugin's C
// callbacks into them when it registers them.
//
// Thread safety: every function here may be called from any thread. Registration (loading a
// plugin) is serialised and transactional: a plugin's entries become visible all at once when
// its register function has succeeded, or not at all. Entries are never removed or changed once
// visible, so the pointers returned by the find_* functions stay valid for the life of the
// process and may be used while other threads load plugins.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/texture_codes.hpp"

namespace occseg {

namespace detail {
struct MapRowSink;  // the fused map pass's per-row sink (pipeline/map_pass.hpp)
}
namespace kernels {
struct Table;  // the kernels of a call (kernels/kernels.hpp)
}

// Name of the plugin that owns the built-in stages and parameters.
constexpr const char* kBuiltinPlugin = "builtin";

struct TextureOperator {
  std::string name, description, plugin;
  // The operator through its plugin's callback: every voxel's code, checked against the count of
  // distinct codes it returns (TextureMap::codes_total). Throws Error(plugin) naming the operator
  // when the callback fails or returns invalid codes.
  std::function<TextureMap(const Grid& grid, const Params& params)> compute;
  // Built-in operators only: a direct C++ implementation the pipeline prefers (no copy). It must
  // reject values outside [0, 1] itself, as compute_texture() does: segment() leaves the value
  // check to an operator that has one, and checks the map first for the others.
  TextureMap (*native)(const Grid& grid, const Params& params) = nullptr;
  // Built-in operators only, optional: `native` writing the codes into caller storage of
  // grid.dims.count() codes instead of a fresh array, with grid.dims.count() bytes of `scratch`
  // it may use meanwhile (or nullptr), with the kernels `k`; returns the number of distinct codes.
  // segment() keeps both in the label array, which it allocates anyway. Its kNoTexture codes must
  // lie only on the map's outer faces (the division counts the blocks inside without testing for
  // them). With `rows` (else nullptr), it hands every row of the map to it as it reads them, as
  // map_pass.hpp's MapRowSink says, so that the creation need not read the map again.
  int (*native_into)(const Grid& grid, const Params& params, const kernels::Table& k, std::uint16_t* codes,
                     std::uint8_t* scratch, const detail::MapRowSink* rows) = nullptr;
};

struct Similarity {
  std::string name, description, plugin;
  // The plugin's measure of two histograms of `bins` counts, as it returned it (compare_histograms
  // checks it).
  std::function<double(const std::uint32_t* a, const std::uint32_t* b, std::size_t bins)> compare;
};

struct MapReader {
  std::string extension, description, plugin;  // extension: lower case, with the dot
  // Reads the map at `path`; throws Error with the reader's status and message on failure.
  std::function<Grid(const std::string& path, const std::vector<std::string>& options)> read;
};

struct MapWriter {
  std::string extension, description, plugin;
  // Writes `grid` to `path`; throws Error with the writer's status and message on failure.
  std::function<void(const std::string& path, const Grid& grid, const std::vector<std::string>& options)> write;
};

struct PluginParam {
  std::string name, kind, default_value, description, plugin;  // kind: "int", "double", "string"
  double min = 0, max = 0;
  ParamInfo info{};  // the same, pointing into this entry (set when it is registered)
};

struct PluginInfo {
  std::string name, version, description, path;  // path: "" for built-ins
  std::uint32_t abi_major = 0, abi_minor = 0;
  std::vector<std::string> textures, similarities, readers, writers, params;
};

// Lookups; nullptr when nothing of that name (extension) is registered.
const TextureOperator* find_texture(const std::string& name);
const Similarity* find_similarity(const std::string& name);
const MapReader* find_reader(const std::string& extension);
const MapWriter* find_writer(const std::string& extension);
const PluginParam* find_plugin_param(const std::string& name);

// Snapshots, in registration order.
std::vector<const PluginInfo*> loaded_plugins();
std::vector<const TextureOperator*> texture_operators();
std::vector<const Similarity*> similarities();
std::vector<const MapReader*> map_readers();
std::vector<const MapWriter*> map_writers();
std::vector<const PluginParam*> plugin_params();

// "a, b, c": the registered names of one kind, for error messages.
std::string texture_names();
std::string similarity_names();

// Loads one plugin file (dlopen, entry point, ABI check, register function). Throws
// Error(plugin) "plugin '<path>': <reason>" and leaves the registry unchanged on any failure.
// Returns the plugin's name.
std::string load_plugin(const std::string& path);

// The folders load_default_plugins() searches, in order: each entry of OCCSEG_PLUGIN_PATH
// (colon-separated), then the install's plugin folder (<libdir>/occseg/plugins, found relative
// to the running binary for relocated installs, then at its configured location).
std::vector<std::string> plugin_search_path();

struct PluginLoadReport {
  std::vector<std::string> loaded;   // names of the plugins loaded now
  std::vector<std::string> skipped;  // files whose plugin name was already loaded (first wins)
  std::vector<std::string> errors;   // one message per file that failed
};
// Loads every "*.so" file of the search path, in folder order then name order. A plugin whose
// name is already loaded (earlier in the path, or before) is skipped; a failing file does not
// stop the others.
PluginLoadReport load_default_plugins();

// The texture stage: runs the operator params.texture. Throws Error(invalid_argument) for an
// unknown name and Error(plugin) when an operator fails or returns invalid codes.
TextureMap run_texture(const Grid& grid, const Params& params);

// The similarity params.similarity for the division, or nullptr for "g" (the division's own
// optimised G-statistic). Throws Error(invalid_argument) for an unknown name.
const Similarity* division_similarity(const Params& params);

// Calls a similarity; throws Error(plugin) for a NaN or negative result.
double compare_histograms(const Similarity& s, const std::uint32_t* a, const std::uint32_t* b, std::size_t bins);

// Reads a map with the reader registered for the file's extension (options: "key=value").
// Throws Error(unsupported) naming the extension when no reader has it.
Grid read_map(const std::string& path, const std::vector<std::string>& options = {});
// Writes a map with the writer registered for the file's extension.
void write_map(const std::string& path, const Grid& grid, const std::vector<std::string>& options = {});

// The lower-case last extension of a path, with its dot ("" when there is none).
std::string file_extension(const std::string& path);

}  // namespace occseg
