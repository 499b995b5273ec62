// occseg_plugin*, occseg_stage*, occseg_param_plugin/_default and the extension-dispatching map
// readers and writers: the C face of the registry (occseg/registry.hpp).
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>

#include "builtin_io.hpp"
#include "internal.hpp"
#include "occseg/occseg_plugin.h"
#include "nrrd_space.hpp"
#include "occseg/geometry.hpp"
#include "occseg/registry.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::copy_text;
using occseg::capi::guard;
using occseg::capi::index_out_of_range;
using occseg::capi::require;

namespace {

// Every function here registers the built-in readers and writers before it reads or extends the
// registry's plugins, readers or writers (builtin_io.hpp); the ones that return a status through
// register_builtin_io, which throws. Those that return no status call this instead: a failure (out
// of memory) leaves them listing what is registered, and the next call with a status reports it.
void builtin_io_quietly() noexcept {
  try {
    occseg::capi::register_builtin_io();
  } catch (...) {
  }
}

const occseg::PluginInfo* plugin_at(uint32_t index) {
  builtin_io_quietly();
  const auto v = occseg::loaded_plugins();
  return index < v.size() ? v[index] : nullptr;
}

struct StageText {
  const char* name;
  const char* description;
  const char* plugin;
};

template <class T>
bool pick(const std::vector<const T*>& v, uint32_t index, const std::string T::*key, StageText& out) {
  if (index >= v.size()) return false;
  out = {(v[index]->*key).c_str(), v[index]->description.c_str(), v[index]->plugin.c_str()};
  return true;
}

// Entries are never removed, so the strings stay valid after the snapshot is gone.
bool stage_at(int kind, uint32_t index, StageText& out) {
  builtin_io_quietly();
  switch (kind) {
    case OCCSEG_STAGE_TEXTURE: return pick(occseg::texture_operators(), index, &occseg::TextureOperator::name, out);
    case OCCSEG_STAGE_SIMILARITY: return pick(occseg::similarities(), index, &occseg::Similarity::name, out);
    case OCCSEG_STAGE_READER: return pick(occseg::map_readers(), index, &occseg::MapReader::extension, out);
    case OCCSEG_STAGE_WRITER: return pick(occseg::map_writers(), index, &occseg::MapWriter::extension, out);
    default: return false;
  }
}

std::vector<std::string> option_list(const char* const* options) {
  std::vector<std::string> v;
  for (const char* const* o = options; o && *o; ++o) v.emplace_back(*o);
  return v;
}

// The default plugin search path, loaded at most once per process: by the first read or write
// whose extension nothing registered serves (as the occseg command loads it at start), or by an
// explicit occseg_plugins_load_default. `done` is set (release) only after `failures` is final,
// so a reader that sees it (acquire) may read `failures` without the mutex.
struct DefaultPlugins {
  std::mutex mutex;
  std::atomic<bool> done{false};
  std::string failures;  // "; "-joined errors of that load
};

DefaultPlugins& default_plugins() {
  static DefaultPlugins d;
  return d;
}

// OCCSEG_NO_DEFAULT_PLUGINS set to anything but "" or "0" turns the loading on first use off.
bool auto_load_disabled() {
  const char* v = std::getenv("OCCSEG_NO_DEFAULT_PLUGINS");
  return v && *v && std::strcmp(v, "0") != 0;
}

std::string joined(const std::vector<std::string>& v) {
  std::string all;
  for (const auto& e : v) all += (all.empty() ? "" : "; ") + e;
  return all;
}

// Runs occseg::load_default_plugins() and marks the search path as loaded; with `once`, only if
// no call has loaded it yet (threads racing to the first read wait for the one that loads).
occseg::PluginLoadReport load_defaults(bool once) {
  occseg::capi::register_builtin_io();
  DefaultPlugins& d = default_plugins();
  const std::lock_guard<std::mutex> lock(d.mutex);
  if (once && d.done.load(std::memory_order_relaxed)) return {};
  occseg::PluginLoadReport r = occseg::load_default_plugins();
  if (!d.done.load(std::memory_order_relaxed)) {
    d.failures = joined(r.errors);
    d.done.store(true, std::memory_order_release);
  }
  return r;
}

std::string search_path_text() {
  std::string s;
  for (const auto& dir : occseg::plugin_search_path()) s += (s.empty() ? "" : ":") + dir;
  return s;
}

// Called when no reader (writer) serves `ext`: loads the default search path once, unless turned
// off. Returns "" when a reader (writer) is registered now, else the text the error gets: what was
// searched and the call or variable that would help.
std::string serve_extension(const std::string& ext, bool reader) {
  auto served = [&] { return reader ? occseg::find_reader(ext) != nullptr : occseg::find_writer(ext) != nullptr; };
  if (ext.empty() || served()) return "";
  DefaultPlugins& d = default_plugins();
  if (!d.done.load(std::memory_order_acquire) && auto_load_disabled()) {
    return "; the default plugin search path (" + search_path_text() +
           ") was not loaded because OCCSEG_NO_DEFAULT_PLUGINS is set: call occseg_plugins_load_default() or "
           "occseg_plugins_load(\"/path/to/plugin.so\")";
  }
  if (!d.done.load(std::memory_order_acquire)) load_defaults(true);
  if (served()) return "";
  std::string hint = "; no plugin of the default search path (" + search_path_text() + ") " +
                     (reader ? "reads" : "writes") +
                     " it: load one with occseg_plugins_load(\"/path/to/plugin.so\") or put its folder on "
                     "OCCSEG_PLUGIN_PATH";
  if (!d.failures.empty()) hint += " (plugins that failed to load: " + d.failures + ")";
  return hint;
}

// The registry's "no reader/writer" error, with `hint` appended; other errors as they are.
template <class Body>
void with_hint(const std::string& hint, Body&& body) {
  if (hint.empty()) return body();
  try {
    body();
  } catch (const Error& e) {
    if (e.status() != Status::unsupported) throw;
    throw Error(e.status(), e.what() + hint);
  }
}

}  // namespace

extern "C" {

int occseg_plugins_load(const char* path) {
  return guard("occseg_plugins_load", [&] {
    require(path, "path");
    occseg::capi::register_builtin_io();
    occseg::load_plugin(path);
  });
}

int occseg_plugins_load_default(uint32_t* loaded) {
  return guard("occseg_plugins_load_default", [&] {
    if (loaded) *loaded = 0;
    const occseg::PluginLoadReport r = load_defaults(false);
    if (loaded) *loaded = static_cast<uint32_t>(r.loaded.size());
    if (!r.errors.empty()) throw Error(Status::plugin, joined(r.errors));
  });
}

int occseg_plugin_search_path(char* buf, size_t size, size_t* length) {
  return guard("occseg_plugin_search_path", [&] {
    std::string s;
    for (const auto& d : occseg::plugin_search_path()) s += (s.empty() ? "" : ":") + d;
    copy_text(s, buf, size, length);
  });
}

uint32_t occseg_plugin_count(void) {
  builtin_io_quietly();
  return static_cast<uint32_t>(occseg::loaded_plugins().size());
}

const char* occseg_plugin_name(uint32_t index) {
  const auto* p = plugin_at(index);
  return p ? p->name.c_str() : nullptr;
}

const char* occseg_plugin_version(uint32_t index) {
  const auto* p = plugin_at(index);
  return p ? p->version.c_str() : nullptr;
}

const char* occseg_plugin_description(uint32_t index) {
  const auto* p = plugin_at(index);
  return p ? p->description.c_str() : nullptr;
}

const char* occseg_plugin_path(uint32_t index) {
  const auto* p = plugin_at(index);
  return p ? p->path.c_str() : nullptr;
}

int occseg_plugin_abi(uint32_t index, uint32_t* major, uint32_t* minor) {
  return guard("occseg_plugin_abi", [&] {
    require(major, "major");
    require(minor, "minor");
    const auto* p = plugin_at(index);
    if (!p) index_out_of_range(index, occseg_plugin_count(), "plugins");
    *major = p->abi_major;
    *minor = p->abi_minor;
  });
}

void occseg_plugin_host_abi(uint32_t* major, uint32_t* minor) {
  if (major) *major = OCCSEG_PLUGIN_ABI_MAJOR;
  if (minor) *minor = OCCSEG_PLUGIN_ABI_MINOR;
}

uint32_t occseg_stage_count(occseg_stage_kind kind) {
  builtin_io_quietly();
  switch (occseg::capi::enum_value(kind)) {
    case OCCSEG_STAGE_TEXTURE: return static_cast<uint32_t>(occseg::texture_operators().size());
    case OCCSEG_STAGE_SIMILARITY: return static_cast<uint32_t>(occseg::similarities().size());
    case OCCSEG_STAGE_READER: return static_cast<uint32_t>(occseg::map_readers().size());
    case OCCSEG_STAGE_WRITER: return static_cast<uint32_t>(occseg::map_writers().size());
    default: return 0;
  }
}

const char* occseg_stage_name(occseg_stage_kind kind, uint32_t index) {
  StageText t{};
  return stage_at(occseg::capi::enum_value(kind), index, t) ? t.name : nullptr;
}

const char* occseg_stage_description(occseg_stage_kind kind, uint32_t index) {
  StageText t{};
  return stage_at(occseg::capi::enum_value(kind), index, t) ? t.description : nullptr;
}

const char* occseg_stage_plugin(occseg_stage_kind kind, uint32_t index) {
  StageText t{};
  return stage_at(occseg::capi::enum_value(kind), index, t) ? t.plugin : nullptr;
}

const char* occseg_param_plugin(uint32_t index) {
  const auto& builtin = occseg::param_table();
  if (index < builtin.size()) return occseg::kBuiltinPlugin;
  const auto declared = occseg::plugin_params();
  index -= static_cast<uint32_t>(builtin.size());
  return index < declared.size() ? declared[index]->plugin.c_str() : nullptr;
}

int occseg_param_default(uint32_t index, char* buf, size_t size, size_t* length) {
  return guard("occseg_param_default", [&] {
    const auto all = occseg::all_params();
    if (index >= all.size()) index_out_of_range(index, all.size(), "parameters");
    copy_text(occseg::param_default(all[index].name), buf, size, length);
  });
}

int occseg_map_read_options(occseg_map** out, const char* path, const char* const* options) {
  return guard("occseg_map_read", [&] {
    require(out, "out");
    *out = nullptr;
    require(path, "path");
    occseg::capi::register_builtin_io();
    auto m = std::make_unique<occseg_map>();
    const occseg::capi::NrrdSpaceScope space;  // the built-in .nrrd reader reports the file's space
    const std::string ext = occseg::file_extension(path);
    const std::string hint = occseg::find_reader(ext) ? "" : serve_extension(ext, true);
    with_hint(hint, [&] { m->grid = occseg::read_map(path, option_list(options)); });
    try {  // a plugin's reader too: every map the C ABI hands out can be written and read back
      occseg::check_geometry(m->grid);
    } catch (const Error& e) {
      throw Error(e.status(), std::string("'") + path + "': " + e.what());
    }
    m->nrrd_space = space.value();
    *out = m.release();
  });
}

int occseg_map_write_options(const occseg_map* map, const char* path, const char* const* options) {
  return guard("occseg_map_write", [&] {
    require(map, "map");
    require(path, "path");
    occseg::capi::register_builtin_io();
    const occseg::capi::NrrdSpaceScope space(map->nrrd_space);  // for the built-in .nrrd writer
    const std::string ext = occseg::file_extension(path);
    const std::string hint = occseg::find_writer(ext) ? "" : serve_extension(ext, false);
    with_hint(hint, [&] {
      if (map->is_view)  // checked as a copy would have been, before anything is written
        occseg::write_map(path, occseg::capi::converted(map), option_list(options));
      else
        occseg::write_map(path, map->grid, option_list(options));
    });
  });
}

}  // extern "C"
