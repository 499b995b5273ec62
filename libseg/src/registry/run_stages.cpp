// Running registered stages (part of the plugin host): the C++ callables around plugins' C
// callbacks, the texture operator and the similarity the parameters name, map readers and
// writers by extension, and the host functions callbacks use while they run.
#include <cmath>
#include <cstring>
#include <sstream>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "occseg/plugin_host.hpp"
#include "occseg/registry.hpp"
#include "registry/registry_internal.hpp"
#include "stages/quantise.hpp"
#include "stages/texture.hpp"

struct occseg_plugin_map_sink {
  occseg::Grid grid;
  bool filled = false;
};

namespace occseg {

namespace {

occseg_plugin_grid grid_view(const Grid& g) {
  occseg_plugin_grid v{};
  v.struct_size = sizeof v;
  v.dims[0] = g.dims.nx;
  v.dims[1] = g.dims.ny;
  v.dims[2] = g.dims.nz;
  v.values = g.values();
  v.voxel_size = g.voxel_size;
  for (int k = 0; k < 3; ++k) v.origin[k] = g.origin[k];
  return v;
}

occseg_plugin_call make_call(void* user, const Params* params) {
  occseg_plugin_call c{};
  c.struct_size = sizeof c;
  c.threads = static_cast<uint32_t>(resolve_threads(params ? params->threads : 0));
  c.host = &host_table();
  c.user = user;
  c.params = params;
  return c;
}

// A plugin's failure code as a status: its own OCCSEG_E* code when it is one, else EPLUGIN.
Status status_of(long long rc) {
  return rc <= -1 && rc >= -11 ? static_cast<Status>(rc) : Status::plugin;
}

std::string coords(const Dims& d, std::size_t i) {
  return "(" + std::to_string(i % d.nx) + ", " + std::to_string(i / d.nx % d.ny) + ", " +
         std::to_string(i / (d.nx * d.ny)) + ")";
}

std::vector<const char*> option_array(const std::vector<std::string>& options) {
  std::vector<const char*> v;
  for (const auto& o : options) v.push_back(o.c_str());
  v.push_back(nullptr);
  return v;
}

template <class T>
std::string extension_list(const std::vector<const T*>& v) {
  std::string s;
  for (const T* e : v) s += (s.empty() ? "" : ", ") + e->extension;
  return s.empty() ? "none" : s;
}

// Host getters: the value of a parameter of the stage's Params, as text, or a refusal.
int param_text(const occseg_plugin_call* call, const char* name, std::string& out) {
  if (!call || !name) {
    set_plugin_error("param_get: NULL call or name");
    return OCCSEG_EINVAL;
  }
  if (!call->params) {
    set_plugin_error(std::string("param_get '") + name + "': no parameters in this callback (readers and writers have none)");
    return OCCSEG_EINVAL;
  }
  try {
    out = get_param(*static_cast<const Params*>(call->params), name);
    return 0;
  } catch (const Error& e) {
    set_plugin_error(e.what());
    return static_cast<int>(e.status());
  }
}

}  // namespace

int host_param_get_int(const occseg_plugin_call* call, const char* name, int64_t* out) {
  std::string t;
  if (int rc = param_text(call, name, t)) return rc;
  const ParamInfo* i = find_param(name);
  if (!out || !i || std::strcmp(i->kind, "int") != 0) {
    set_plugin_error(std::string("param_get_int '") + name + "': not an int parameter (or out is NULL)");
    return OCCSEG_EINVAL;
  }
  *out = std::strtoll(t.c_str(), nullptr, 10);
  return 0;
}

int host_param_get_double(const occseg_plugin_call* call, const char* name, double* out) {
  std::string t;
  if (int rc = param_text(call, name, t)) return rc;
  const ParamInfo* i = find_param(name);
  if (!out || !i || std::strcmp(i->kind, "string") == 0) {
    set_plugin_error(std::string("param_get_double '") + name + "': not a number parameter (or out is NULL)");
    return OCCSEG_EINVAL;
  }
  *out = std::strtod(t.c_str(), nullptr);
  return 0;
}

int host_param_get_string(const occseg_plugin_call* call, const char* name, char* buf, size_t size) {
  std::string t;
  if (int rc = param_text(call, name, t)) return rc;
  if (!buf || size < t.size() + 1) {
    set_plugin_error(std::string("param_get_string '") + name + "': buffer of " + std::to_string(size) +
                     " bytes is too small for '" + t + "'");
    return OCCSEG_ERANGE;
  }
  std::memcpy(buf, t.c_str(), t.size() + 1);
  return 0;
}

void deliver_grid(occseg_plugin_map_sink* sink, Grid&& grid) {
  sink->grid = std::move(grid);
  sink->filled = true;
}

int host_map_alloc(occseg_plugin_map_sink* sink, const size_t dims[3], double voxel_size, const double origin[3],
                   float** values) {
  if (!sink || !dims || !values) {
    set_plugin_error("map_alloc: NULL sink, dims or values");
    return OCCSEG_EINVAL;
  }
  *values = nullptr;
  if (!(voxel_size > 0) || !std::isfinite(voxel_size)) {
    set_plugin_error("map_alloc: voxel_size " + std::to_string(voxel_size) + " is not a positive finite number");
    return OCCSEG_EVALUE;
  }
  try {
    Grid g(Dims{dims[0], dims[1], dims[2]}, 0.5f, voxel_size);
    if (origin)
      for (int k = 0; k < 3; ++k) g.origin[k] = origin[k];
    sink->grid = std::move(g);
    sink->filled = true;
    *values = sink->grid.p.data();
    return 0;
  } catch (const Error& e) {
    set_plugin_error(std::string("map_alloc: ") + e.what());
    return static_cast<int>(e.status());
  } catch (const std::bad_alloc&) {
    set_plugin_error("map_alloc: out of memory");
    return OCCSEG_ENOMEM;
  }
}

int host_contrast_levels(const double* contrast, size_t count, uint32_t bins, uint16_t* levels) {
  if ((!contrast || !levels) && count) {
    set_plugin_error("contrast_levels: NULL contrast or levels");
    return OCCSEG_EINVAL;
  }
  if (bins < 2 || bins > 64) {
    set_plugin_error("contrast_levels: bins " + std::to_string(bins) + " is outside [2, 64]");
    return OCCSEG_EINVAL;
  }
  try {
    // The same fine steps and quantiser as the built-in 6-neighbour operator.
    quantise_contrasts(contrast, count, static_cast<int>(bins), levels, static_cast<std::uint16_t>(OCCSEG_NO_TEXTURE));
    return 0;
  } catch (const std::bad_alloc&) {
    set_plugin_error("contrast_levels: out of memory");
    return OCCSEG_ENOMEM;
  }
}

std::function<TextureMap(const Grid&, const Params&)> plugin_texture(occseg_plugin_texture_fn fn, void* user,
                                                                     const std::string& name, const std::string& plugin) {
  const std::string who = "texture operator '" + name + "' (plugin '" + plugin + "')";
  return [fn, user, who](const Grid& grid, const Params& params) {
    TextureMap tm;
    tm.bins = params.contrast_bins;
    tm.codes.assign(grid.dims.count(), static_cast<std::uint16_t>(OCCSEG_NO_TEXTURE));
    const occseg_plugin_grid view = grid_view(grid);
    const occseg_plugin_call call = make_call(user, &params);
    clear_plugin_error();
    int64_t k = 0;
    try {
      k = fn(&call, &view, static_cast<uint32_t>(params.contrast_bins), tm.codes.data());
    } catch (...) {
      throw Error(Status::plugin, who + ": an exception escaped the callback");
    }
    if (k < 0) throw Error(status_of(k), who + " failed: " + plugin_error());
    if (k == 0 || k > 65535)
      throw Error(Status::plugin, who + " returned " + std::to_string(k) + " codes (must be 1 .. 65535)");
    // A code past the histogram would be written out of bounds by the division: check them all.
    for (std::size_t i = 0; i < tm.codes.size(); ++i)
      if (tm.codes[i] >= k && tm.codes[i] != OCCSEG_NO_TEXTURE)
        throw Error(Status::plugin, who + ": code " + std::to_string(tm.codes[i]) + " at voxel " + coords(grid.dims, i) +
                                        " is outside [0, " + std::to_string(k) + ")");
    tm.codes_total = static_cast<int>(k);
    return tm;
  };
}

std::function<double(const std::uint32_t*, const std::uint32_t*, std::size_t)> plugin_similarity(
    occseg_plugin_similarity_fn fn, void* user) {
  return [fn, user](const std::uint32_t* a, const std::uint32_t* b, std::size_t bins) {
    const occseg_plugin_call call = make_call(user, nullptr);
    return fn(&call, a, b, bins);
  };
}

std::function<Grid(const std::string&, const std::vector<std::string>&)> plugin_reader(occseg_plugin_read_fn fn, void* user,
                                                                                        const std::string& plugin) {
  return [fn, user, plugin](const std::string& path, const std::vector<std::string>& options) {
    occseg_plugin_map_sink sink;
    const auto opts = option_array(options);
    const occseg_plugin_call call = make_call(user, nullptr);
    clear_plugin_error();
    int rc = 0;
    try {
      rc = fn(&call, path.c_str(), opts.data(), &sink);
    } catch (...) {
      throw Error(Status::plugin, "'" + path + "': an exception escaped the reader of plugin '" + plugin + "'");
    }
    const std::string by = plugin == kBuiltinPlugin ? "" : " [reader of plugin '" + plugin + "']";
    if (rc != 0) throw Error(status_of(rc), plugin_error() + by);
    if (!sink.filled) throw Error(Status::plugin, "'" + path + "': the reader returned no map" + by);
    return std::move(sink.grid);
  };
}

std::function<void(const std::string&, const Grid&, const std::vector<std::string>&)> plugin_writer(
    occseg_plugin_write_fn fn, void* user, const std::string& plugin) {
  return [fn, user, plugin](const std::string& path, const Grid& grid, const std::vector<std::string>& options) {
    const occseg_plugin_grid view = grid_view(grid);
    const auto opts = option_array(options);
    const occseg_plugin_call call = make_call(user, nullptr);
    clear_plugin_error();
    int rc = 0;
    try {
      rc = fn(&call, path.c_str(), &view, opts.data());
    } catch (...) {
      throw Error(Status::plugin, "'" + path + "': an exception escaped the writer of plugin '" + plugin + "'");
    }
    if (rc != 0)
      throw Error(status_of(rc), plugin_error() + (plugin == kBuiltinPlugin ? "" : " [writer of plugin '" + plugin + "']"));
  };
}

TextureMap run_texture(const Grid& grid, const Params& params) {
  const std::string name = resolved_texture(params, grid.dims);
  const TextureOperator* op = find_texture(name);
  if (!op)
    throw Error(Status::invalid_argument, "parameter 'texture': no texture operator '" + name +
                                              "' is registered (registered: " + texture_names() + ")");
  return op->native ? op->native(grid, params) : op->compute(grid, params);
}

const Similarity* division_similarity(const Params& params) {
  const Similarity* s = find_similarity(params.similarity);
  if (!s)
    throw Error(Status::invalid_argument, "parameter 'similarity': no similarity '" + params.similarity +
                                              "' is registered (registered: " + similarity_names() + ")");
  return s->plugin == kBuiltinPlugin && s->name == "g" ? nullptr : s;
}

double compare_histograms(const Similarity& s, const std::uint32_t* a, const std::uint32_t* b, std::size_t bins) {
  const double v = s.compare(a, b, bins);
  if (!(v >= 0)) {  // NaN too
    std::ostringstream o;
    o << "similarity '" << s.name << "' (plugin '" << s.plugin << "') returned " << v << " (must be >= 0)";
    throw Error(Status::plugin, o.str());
  }
  return v;
}

Grid read_map(const std::string& path, const std::vector<std::string>& options) {
  const std::string ext = file_extension(path);
  const MapReader* r = find_reader(ext);
  if (!r)
    throw Error(Status::unsupported, "'" + path + "': no reader for " +
                                         (ext.empty() ? std::string("a file without extension") : "extension '" + ext + "'") +
                                         " (readers: " + extension_list(map_readers()) + "; plugins add others)");
  Grid grid = r->read(path, options);
  try {
    check_probabilities(grid);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what() +
                                (r->plugin == kBuiltinPlugin ? "" : " [reader of plugin '" + r->plugin + "']"));
  }
  return grid;
}

void write_map(const std::string& path, const Grid& grid, const std::vector<std::string>& options) {
  const std::string ext = file_extension(path);
  const MapWriter* w = find_writer(ext);
  if (!w)
    throw Error(Status::unsupported, "'" + path + "': no writer for " +
                                         (ext.empty() ? std::string("a file without extension") : "extension '" + ext + "'") +
                                         " (writers: " + extension_list(map_writers()) + "; plugins add others)");
  w->write(path, grid, options);
}

}  // namespace occseg
