// Loading plugin files: dlopen, the entry point, and the default search path
// (OCCSEG_PLUGIN_PATH, then the install's <libdir>/occseg/plugins).
#include <dirent.h>
#include <dlfcn.h>
#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "occseg/error.hpp"
#include "occseg/registry.hpp"
#include "registry/registry_internal.hpp"

// Set by libseg/CMakeLists.txt: the configured install folder, and the same folder relative to
// the library folder and to the program folder (for installs moved after building).
#ifndef OCCSEG_PLUGIN_INSTALL_DIR
#define OCCSEG_PLUGIN_INSTALL_DIR "/usr/local/lib/occseg/plugins"
#endif
#ifndef OCCSEG_PLUGIN_DIR_FROM_LIB
#define OCCSEG_PLUGIN_DIR_FROM_LIB "occseg/plugins"
#endif
#ifndef OCCSEG_PLUGIN_DIR_FROM_BIN
#define OCCSEG_PLUGIN_DIR_FROM_BIN "../lib/occseg/plugins"
#endif

namespace occseg {

namespace {

std::string dl_error() {
  const char* e = dlerror();
  return e ? e : "no dlerror() text";
}

std::string real_path(const std::string& p) {
  char buf[PATH_MAX];
  return ::realpath(p.c_str(), buf) ? std::string(buf) : std::string();
}

std::string dir_of(const std::string& p) {
  const std::size_t s = p.find_last_of('/');
  return s == std::string::npos ? "." : p.substr(0, s);
}

bool is_dir(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

// The plugin folder next to the binary this code is linked into: <dir>/occseg/plugins for a
// shared library in <prefix>/<libdir>, <dir>/../lib/occseg/plugins for a program in <prefix>/bin.
std::string relocated_dir() {
  Dl_info info{};
  if (!dladdr(reinterpret_cast<void*>(&relocated_dir), &info) || !info.dli_fname) return "";
  const std::string self = real_path(info.dli_fname);
  const std::string exe = real_path("/proc/self/exe");
  if (self.empty() || self == exe) return exe.empty() ? "" : dir_of(exe) + "/" + OCCSEG_PLUGIN_DIR_FROM_BIN;
  return dir_of(self) + "/" + OCCSEG_PLUGIN_DIR_FROM_LIB;
}

// dlopen() of a FIFO waits for a writer forever (every command loads the search path's plugins
// first, --version included) and a device is no library: only regular files are opened. A path
// without a '/' is a name for the loader's own search and is left to it.
void check_plugin_file(const std::string& path) {
  struct stat st {};
  if (path.find('/') == std::string::npos || ::stat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) return;
  throw Error(Status::plugin, "plugin '" + path + "': cannot be loaded: " +
                                  (S_ISDIR(st.st_mode)    ? "it is a directory"
                                   : S_ISFIFO(st.st_mode) ? "it is not a regular file but a FIFO (named pipe)"
                                                          : "it is not a regular file"));
}

// Closes a handle unless released (a failed load leaves nothing behind).
struct Handle {
  void* h = nullptr;
  ~Handle() {
    if (h) dlclose(h);
  }
};

std::vector<std::string> plugin_files(const std::string& dir) {
  std::vector<std::string> files;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* e = ::readdir(d)) {
      const std::string n = e->d_name;
      if (n.size() > 3 && n.compare(n.size() - 3, 3, ".so") == 0) files.push_back(dir + "/" + n);
    }
    ::closedir(d);
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

std::string load_plugin(const std::string& path) {
  find_texture("");  // the built-ins first, so that a plugin cannot take their names
  check_plugin_file(path);
  dlerror();
  Handle h;
  h.h = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!h.h) throw Error(Status::plugin, "plugin '" + path + "': cannot be loaded: " + dl_error());
  dlerror();
  void* sym = dlsym(h.h, OCCSEG_PLUGIN_ENTRY_SYMBOL);
  if (!sym)
    throw Error(Status::plugin, "plugin '" + path + "': no entry point '" + OCCSEG_PLUGIN_ENTRY_SYMBOL +
                                    "' (" + dl_error() + ")");
  occseg_plugin_entry_fn entry;
  static_assert(sizeof entry == sizeof sym, "function and data pointers differ in size");
  std::memcpy(&entry, &sym, sizeof entry);
  const occseg_plugin_descriptor* d = nullptr;
  try {
    d = entry();
  } catch (...) {
    throw Error(Status::plugin, "plugin '" + path + "': an exception escaped its entry point");
  }
  const std::string name = install_descriptor(d, path, h.h);
  h.h = nullptr;  // loaded for good: its callbacks are registered
  return name;
}

std::vector<std::string> plugin_search_path() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("OCCSEG_PLUGIN_PATH")) {
    std::string s = env;
    std::size_t b = 0;
    while (b <= s.size()) {
      std::size_t e = s.find(':', b);
      if (e == std::string::npos) e = s.size();
      if (e > b) dirs.push_back(s.substr(b, e - b));
      b = e + 1;
    }
  }
  const std::string rel = relocated_dir();
  if (!rel.empty()) dirs.push_back(rel);
  dirs.push_back(OCCSEG_PLUGIN_INSTALL_DIR);
  // The same folder twice (the relocated one is usually the configured one) is searched once.
  std::vector<std::string> out, seen;
  for (const auto& d : dirs) {
    const std::string r = real_path(d);
    const std::string key = r.empty() ? d : r;
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;
    seen.push_back(key);
    out.push_back(d);
  }
  return out;
}

PluginLoadReport load_default_plugins() {
  PluginLoadReport report;
  for (const auto& dir : plugin_search_path()) {
    if (!is_dir(dir)) continue;
    for (const auto& file : plugin_files(dir)) {
      try {
        check_plugin_file(file);
      } catch (const Error& e) {
        report.errors.push_back(e.what());
        continue;
      }
      // Peek at the plugin's name first: one already loaded (e.g. the same plugin in an
      // earlier folder of the path) is skipped, not an error.
      void* h = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (h) {
        void* sym = dlsym(h, OCCSEG_PLUGIN_ENTRY_SYMBOL);
        occseg_plugin_entry_fn entry = nullptr;
        if (sym) std::memcpy(&entry, &sym, sizeof entry);
        const occseg_plugin_descriptor* d = entry ? entry() : nullptr;
        const bool skip = d && d->name && plugin_loaded(d->name);
        dlclose(h);
        if (skip) {
          report.skipped.push_back(file);
          continue;
        }
      }
      try {
        report.loaded.push_back(load_plugin(file));
      } catch (const Error& e) {
        report.errors.push_back(e.what());
      }
    }
  }
  return report;
}

}  // namespace occseg
