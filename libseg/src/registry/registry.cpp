// The registry's storage, lookups and transactional registration, and the host table plugins
// register through (occseg_plugin_host). Loading files is plugin_loader.cpp; running the
// registered stages is stages.cpp.
#include "occseg/registry.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <memory>
#include <mutex>
#include <shared_mutex>

#include "occseg/error.hpp"
#include "registry/registry_internal.hpp"

struct occseg_plugin_registrar {
  std::string plugin;  // name of the plugin registering
  bool open = true;    // false once its register function has returned
  std::vector<occseg::TextureOperator> textures;
  std::vector<occseg::Similarity> similarities;
  std::vector<occseg::MapReader> readers;
  std::vector<occseg::MapWriter> writers;
  std::vector<occseg::PluginParam> params;
};

namespace occseg {

namespace {

struct Registry {
  std::shared_mutex tables;  // guards the vectors below (the entries themselves are immutable)
  std::mutex loading;        // one plugin registers at a time
  std::vector<std::unique_ptr<PluginInfo>> plugins;
  std::vector<std::unique_ptr<TextureOperator>> textures;
  std::vector<std::unique_ptr<Similarity>> similarities;
  std::vector<std::unique_ptr<MapReader>> readers;
  std::vector<std::unique_ptr<MapWriter>> writers;
  std::vector<std::unique_ptr<PluginParam>> params;
};

Registry& raw() {
  static Registry r;
  return r;
}

// The registry with the built-in stages in it: they are registered on first use, through the
// same path as every plugin.
Registry& reg() {
  static std::once_flag once;
  std::call_once(once, [] {
    install_descriptor(builtin_stages_descriptor(), "", nullptr);
    attach_builtin_natives();
  });
  return raw();
}

template <class T, class Key>
const T* find_in(const std::vector<std::unique_ptr<T>>& v, const Key& key, std::string T::*field) {
  for (const auto& e : v)
    if ((*e).*field == key) return e.get();
  return nullptr;
}

template <class T>
std::vector<const T*> snapshot(std::vector<std::unique_ptr<T>> Registry::*member) {
  Registry& r = reg();
  std::shared_lock<std::shared_mutex> lock(r.tables);
  std::vector<const T*> out;
  for (const auto& e : r.*member) out.push_back(e.get());
  return out;
}

template <class T>
std::string join_names(const std::vector<const T*>& v) {
  std::string s;
  for (const T* e : v) s += (s.empty() ? "" : ", ") + e->name;
  return s.empty() ? "none" : s;
}

thread_local std::string t_plugin_error;

// ---- The host table -------------------------------------------------------------------------

bool valid_name(const char* n) {
  if (!n || !*n || std::strlen(n) > 63) return false;
  for (const char* c = n; *c; ++c)
    if (!(std::islower(static_cast<unsigned char>(*c)) || std::isdigit(static_cast<unsigned char>(*c)) || *c == '_'))
      return false;
  return true;
}

bool valid_extension(const char* e) {
  if (!e || e[0] != '.' || !e[1] || std::strlen(e) > 31) return false;
  for (const char* c = e + 1; *c; ++c)
    if (!std::isalnum(static_cast<unsigned char>(*c)) && *c != '_' && *c != '-') return false;
  return true;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Every host function reports a failure the same way: the text for occseg_last_error, a code.
int refuse(int code, const std::string& message) {
  t_plugin_error = message;
  return code;
}

// Common checks of a registration: an open registrar, a struct of at least the 1.0 size.
template <class S>
int check_call(occseg_plugin_registrar* r, const S* s, const char* what) {
  if (!r || !s) return refuse(OCCSEG_EINVAL, std::string(what) + ": NULL registrar or struct");
  if (!r->open)
    return refuse(OCCSEG_EINVAL, std::string(what) + ": called after the register function returned");
  if (s->struct_size < sizeof(S))
    return refuse(OCCSEG_EINVAL, std::string(what) + ": struct_size " + std::to_string(s->struct_size) +
                                     " is smaller than the " + std::to_string(sizeof(S)) + " bytes of ABI 1.0");
  return 0;
}

std::string text(const char* s) { return s ? s : ""; }

// A stage name taken by a committed entry (of any plugin) or by this plugin already.
template <class T>
std::string owner_of(const std::vector<std::unique_ptr<T>>& committed, const std::vector<T>& pending,
                     const std::string& key, std::string T::*field) {
  for (const auto& e : committed)
    if ((*e).*field == key) return e->plugin;
  for (const auto& e : pending)
    if (e.*field == key) return e.plugin;
  return "";
}

int host_register_texture(occseg_plugin_registrar* r, const occseg_plugin_texture* t) {
  if (int rc = check_call(r, t, "register_texture")) return rc;
  if (!valid_name(t->name)) return refuse(OCCSEG_EINVAL, "register_texture: name '" + text(t->name) + "' is not 1-63 characters of [a-z0-9_]");
  if (!t->compute) return refuse(OCCSEG_EINVAL, std::string("register_texture '") + t->name + "': compute is NULL");
  Registry& g = raw();
  std::shared_lock<std::shared_mutex> lock(g.tables);
  const std::string owner = owner_of(g.textures, r->textures, t->name, &TextureOperator::name);
  if (!owner.empty())
    return refuse(OCCSEG_EPLUGIN, std::string("texture operator '") + t->name + "' is already registered by plugin '" + owner + "'");
  r->textures.push_back({t->name, text(t->description), r->plugin, plugin_texture(t->compute, t->user, t->name, r->plugin)});
  return 0;
}

int host_register_similarity(occseg_plugin_registrar* r, const occseg_plugin_similarity* s) {
  if (int rc = check_call(r, s, "register_similarity")) return rc;
  if (!valid_name(s->name)) return refuse(OCCSEG_EINVAL, "register_similarity: name '" + text(s->name) + "' is not 1-63 characters of [a-z0-9_]");
  if (!s->compare) return refuse(OCCSEG_EINVAL, std::string("register_similarity '") + s->name + "': compare is NULL");
  Registry& g = raw();
  std::shared_lock<std::shared_mutex> lock(g.tables);
  const std::string owner = owner_of(g.similarities, r->similarities, s->name, &Similarity::name);
  if (!owner.empty())
    return refuse(OCCSEG_EPLUGIN, std::string("similarity '") + s->name + "' is already registered by plugin '" + owner + "'");
  r->similarities.push_back({s->name, text(s->description), r->plugin, plugin_similarity(s->compare, s->user)});
  return 0;
}

template <class S, class E, class Fn, class Wrap>
int register_file_kind(occseg_plugin_registrar* r, const S* s, const char* what, Fn fn, Wrap wrap,
                       std::vector<std::unique_ptr<E>> Registry::*committed, std::vector<E> occseg_plugin_registrar::*pending) {
  if (int rc = check_call(r, s, what)) return rc;
  if (!valid_extension(s->extension))
    return refuse(OCCSEG_EINVAL, std::string(what) + ": extension '" + text(s->extension) + "' is not a dot followed by 1-30 of [A-Za-z0-9_-]");
  if (!fn) return refuse(OCCSEG_EINVAL, std::string(what) + " '" + s->extension + "': callback is NULL");
  const std::string ext = lower(s->extension);
  Registry& g = raw();
  std::shared_lock<std::shared_mutex> lock(g.tables);
  const std::string owner = owner_of(g.*committed, r->*pending, ext, &E::extension);
  if (!owner.empty())
    return refuse(OCCSEG_EPLUGIN, std::string(what) + ": extension '" + ext + "' is already handled by plugin '" + owner + "'");
  (r->*pending).push_back({ext, text(s->description), r->plugin, wrap(fn, s->user, r->plugin)});
  return 0;
}

int host_register_reader(occseg_plugin_registrar* r, const occseg_plugin_reader* s) {
  return register_file_kind(r, s, "register_reader", s ? s->read : nullptr, plugin_reader, &Registry::readers, &occseg_plugin_registrar::readers);
}

int host_register_writer(occseg_plugin_registrar* r, const occseg_plugin_writer* s) {
  return register_file_kind(r, s, "register_writer", s ? s->write : nullptr, plugin_writer, &Registry::writers, &occseg_plugin_registrar::writers);
}

int host_declare_param(occseg_plugin_registrar* r, const occseg_plugin_param* p) {
  if (int rc = check_call(r, p, "declare_param")) return rc;
  if (!valid_name(p->name)) return refuse(OCCSEG_EINVAL, "declare_param: name '" + text(p->name) + "' is not 1-63 characters of [a-z0-9_]");
  const std::string name = p->name;
  static const char* const kinds[] = {"int", "double", "string"};
  if (p->kind < OCCSEG_PARAM_INT || p->kind > OCCSEG_PARAM_STRING)
    return refuse(OCCSEG_EINVAL, "declare_param '" + name + "': kind " + std::to_string(p->kind) + " is not OCCSEG_PARAM_INT, _DOUBLE or _STRING");
  if (!p->default_value) return refuse(OCCSEG_EINVAL, "declare_param '" + name + "': default_value is NULL");
  PluginParam e{name, kinds[p->kind], p->default_value, text(p->description), r->plugin, 0, 0, {}};
  if (p->kind != OCCSEG_PARAM_STRING) {
    if (!(p->min <= p->max)) return refuse(OCCSEG_EINVAL, "declare_param '" + name + "': min is not <= max");
    e.min = p->min;
    e.max = p->max;
    try {
      check_param_value(ParamInfo{e.name.c_str(), e.kind.c_str(), e.min, e.max, ""}, e.default_value);
    } catch (const Error& err) {
      return refuse(OCCSEG_EINVAL, std::string("declare_param: default value: ") + err.what());
    }
  }
  for (const ParamInfo& b : param_table())
    if (name == b.name) return refuse(OCCSEG_EPLUGIN, "parameter '" + name + "' is a built-in parameter");
  Registry& g = raw();
  std::shared_lock<std::shared_mutex> lock(g.tables);
  const std::string owner = owner_of(g.params, r->params, name, &PluginParam::name);
  if (!owner.empty())
    return refuse(OCCSEG_EPLUGIN, "parameter '" + name + "' is already declared by plugin '" + owner + "'");
  r->params.push_back(std::move(e));
  return 0;
}

void host_set_error(const char* message) { t_plugin_error = message ? message : ""; }

}  // namespace

// ---- Internal interface (registry_internal.hpp) ---------------------------------------------

void set_plugin_error(const std::string& message) { t_plugin_error = message; }
void clear_plugin_error() { t_plugin_error.clear(); }
std::string plugin_error() { return t_plugin_error.empty() ? "(no message)" : t_plugin_error; }

const occseg_plugin_host& host_table() {
  static const occseg_plugin_host h = [] {
    occseg_plugin_host t{};
    t.struct_size = sizeof t;
    t.abi_major = OCCSEG_PLUGIN_ABI_MAJOR;
    t.abi_minor = OCCSEG_PLUGIN_ABI_MINOR;
    t.register_texture = host_register_texture;
    t.register_similarity = host_register_similarity;
    t.register_reader = host_register_reader;
    t.register_writer = host_register_writer;
    t.declare_param = host_declare_param;
    t.set_error = host_set_error;
    t.param_get_int = host_param_get_int;
    t.param_get_double = host_param_get_double;
    t.param_get_string = host_param_get_string;
    t.map_alloc = host_map_alloc;
    t.contrast_levels = host_contrast_levels;
    return t;
  }();
  return h;
}

std::string install_descriptor(const occseg_plugin_descriptor* d, const std::string& path, void* handle) {
  (void)handle;  // kept open by the caller once this succeeds
  Registry& g = raw();
  std::lock_guard<std::mutex> loading(g.loading);
  const std::string who = path.empty() ? "built-in plugin" : "plugin '" + path + "'";
  auto fail = [&](const std::string& why) -> std::string { throw Error(Status::plugin, who + ": " + why); };
  if (!d) fail(std::string("the entry point ") + OCCSEG_PLUGIN_ENTRY_SYMBOL + "() returned NULL");
  const std::string host_abi = std::to_string(OCCSEG_PLUGIN_ABI_MAJOR) + "." + std::to_string(OCCSEG_PLUGIN_ABI_MINOR);
  const std::string its_abi = std::to_string(d->abi_major) + "." + std::to_string(d->abi_minor);
  if (d->abi_major != OCCSEG_PLUGIN_ABI_MAJOR)
    fail("ABI mismatch: built for plugin ABI " + its_abi + ", this host speaks " + host_abi + " (the major must match)");
  if (d->abi_minor > OCCSEG_PLUGIN_ABI_MINOR)
    fail("ABI mismatch: built for plugin ABI " + its_abi + ", newer than this host's " + host_abi + " (rebuild it, or update occseg)");
  if (d->struct_size < sizeof(occseg_plugin_descriptor))
    fail("descriptor struct_size " + std::to_string(d->struct_size) + " is smaller than the " +
         std::to_string(sizeof(occseg_plugin_descriptor)) + " bytes of ABI 1.0");
  if (!valid_name(d->name)) fail("descriptor name '" + text(d->name) + "' is not 1-63 characters of [a-z0-9_]");
  if (!d->register_plugin) fail(std::string("plugin '") + d->name + "' has no register function");
  {
    std::shared_lock<std::shared_mutex> lock(g.tables);
    for (const auto& p : g.plugins)
      if (p->name == d->name)
        fail(std::string("a plugin named '") + d->name + "' is already loaded" +
             (p->path.empty() ? " (built in)" : " from '" + p->path + "'"));
  }
  occseg_plugin_registrar r;
  r.plugin = d->name;
  clear_plugin_error();
  int rc = 0;
  try {
    rc = d->register_plugin(&host_table(), &r);
  } catch (...) {  // a C++ plugin let an exception escape: a failure like any other
    rc = OCCSEG_EINTERNAL;
    if (t_plugin_error.empty()) t_plugin_error = "an exception escaped the register function";
  }
  r.open = false;
  if (rc != 0)
    fail(std::string("register function of '") + d->name + "' failed (" + std::to_string(rc) + "): " + plugin_error());
  // Commit: everything at once. Names were checked while registering, under the loading lock,
  // so no other registration can have taken them since.
  auto info = std::make_unique<PluginInfo>();
  info->name = d->name;
  info->version = text(d->version);
  info->description = text(d->description);
  info->path = path;
  info->abi_major = d->abi_major;
  info->abi_minor = d->abi_minor;
  for (const auto& e : r.textures) info->textures.push_back(e.name);
  for (const auto& e : r.similarities) info->similarities.push_back(e.name);
  for (const auto& e : r.readers) info->readers.push_back(e.extension);
  for (const auto& e : r.writers) info->writers.push_back(e.extension);
  for (const auto& e : r.params) info->params.push_back(e.name);
  std::unique_lock<std::shared_mutex> lock(g.tables);
  g.plugins.push_back(std::move(info));
  for (auto& e : r.textures) g.textures.push_back(std::make_unique<TextureOperator>(std::move(e)));
  for (auto& e : r.similarities) g.similarities.push_back(std::make_unique<Similarity>(std::move(e)));
  for (auto& e : r.readers) g.readers.push_back(std::make_unique<MapReader>(std::move(e)));
  for (auto& e : r.writers) g.writers.push_back(std::make_unique<MapWriter>(std::move(e)));
  for (auto& e : r.params) {
    auto p = std::make_unique<PluginParam>(std::move(e));
    p->info = ParamInfo{p->name.c_str(), p->kind.c_str(), p->min, p->max, p->description.c_str()};  // its final address
    g.params.push_back(std::move(p));
  }
  return d->name;
}

void set_native_texture(const std::string& name, TextureMap (*native)(const Grid&, const Params&),
                        int (*native_into)(const Grid&, const Params&, const kernels::Table&, std::uint16_t*,
                                           std::uint8_t*, const detail::MapRowSink*)) {
  Registry& g = raw();
  std::unique_lock<std::shared_mutex> lock(g.tables);
  for (auto& e : g.textures)
    if (e->name == name && e->plugin == kBuiltinPlugin) {
      e->native = native;
      e->native_into = native_into;
    }
}

bool plugin_loaded(const std::string& name) {
  Registry& g = reg();
  std::shared_lock<std::shared_mutex> lock(g.tables);
  for (const auto& p : g.plugins)
    if (p->name == name) return true;
  return false;
}

// ---- Public lookups -------------------------------------------------------------------------

void register_static_plugin(const occseg_plugin_descriptor* descriptor) {
  reg();
  install_descriptor(descriptor, "", nullptr);
}

const TextureOperator* find_texture(const std::string& name) {
  Registry& r = reg();
  std::shared_lock<std::shared_mutex> lock(r.tables);
  return find_in(r.textures, name, &TextureOperator::name);
}

const Similarity* find_similarity(const std::string& name) {
  Registry& r = reg();
  std::shared_lock<std::shared_mutex> lock(r.tables);
  return find_in(r.similarities, name, &Similarity::name);
}

const MapReader* find_reader(const std::string& extension) {
  Registry& r = reg();
  std::shared_lock<std::shared_mutex> lock(r.tables);
  return find_in(r.readers, lower(extension), &MapReader::extension);
}

const MapWriter* find_writer(const std::string& extension) {
  Registry& r = reg();
  std::shared_lock<std::shared_mutex> lock(r.tables);
  return find_in(r.writers, lower(extension), &MapWriter::extension);
}

const PluginParam* find_plugin_param(const std::string& name) {
  Registry& r = reg();
  std::shared_lock<std::shared_mutex> lock(r.tables);
  return find_in(r.params, name, &PluginParam::name);
}

std::vector<const PluginInfo*> loaded_plugins() { return snapshot(&Registry::plugins); }
std::vector<const TextureOperator*> texture_operators() { return snapshot(&Registry::textures); }
std::vector<const Similarity*> similarities() { return snapshot(&Registry::similarities); }
std::vector<const MapReader*> map_readers() { return snapshot(&Registry::readers); }
std::vector<const MapWriter*> map_writers() { return snapshot(&Registry::writers); }
std::vector<const PluginParam*> plugin_params() { return snapshot(&Registry::params); }

std::string texture_names() { return join_names(texture_operators()); }
std::string similarity_names() { return join_names(similarities()); }

std::string file_extension(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) || dot + 1 == path.size()) return "";
  return lower(path.substr(dot));
}

}  // namespace occseg
