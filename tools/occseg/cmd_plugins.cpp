// `occseg plugins [--load FILE]...`: lists the loaded plugins (built-in ones, those of the search
// path, and any named with --load) with their versions, stages and parameters. Also the
// loading every command shares (load_cli_plugins).
#include <sys/stat.h>

#include <iostream>
#include <string>
#include <vector>

#include "builtin_io.hpp"
#include "commands.hpp"
#include "occseg/error.hpp"
#include "occseg/params.hpp"
#include "occseg/occseg_plugin.h"
#include "occseg/registry.hpp"

namespace occseg::cli {

namespace {

bool is_dir(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

void list(std::ostream& out) {
  out << "plugin ABI " << OCCSEG_PLUGIN_ABI_MAJOR << "." << OCCSEG_PLUGIN_ABI_MINOR << "; search path:\n";
  for (const auto& d : plugin_search_path()) out << "  " << d << (is_dir(d) ? "" : " (missing)") << "\n";
  auto describe = [&](const char* kind, const std::string& name, const std::string& text) {
    out << "  " << kind << " " << name << ": " << text << "\n";
  };
  for (const PluginInfo* p : loaded_plugins()) {
    out << "plugin " << p->name << " " << p->version << " (ABI " << p->abi_major << "." << p->abi_minor << ", "
        << (p->path.empty() ? std::string("built in") : p->path) << "): " << p->description << "\n";
    for (const auto* t : texture_operators())
      if (t->plugin == p->name) describe("texture", t->name, t->description);
    for (const auto* s : similarities())
      if (s->plugin == p->name) describe("similarity", s->name, s->description);
    for (const auto* r : map_readers())
      if (r->plugin == p->name) describe("reader", r->extension, r->description);
    for (const auto* w : map_writers())
      if (w->plugin == p->name) describe("writer", w->extension, w->description);
    for (const ParamInfo& i : all_params()) {
      if (param_owner(i.name) != p->name) continue;
      out << "  parameter " << i.name << " (" << i.kind << ", default " << param_default(i.name);
      if (std::string(i.kind) != "string") out << ", in [" << i.min << ", " << i.max << "]";
      out << "): " << i.description << "\n";
    }
  }
}

}  // namespace

void load_cli_plugins() {
  capi::register_builtin_io();  // first: "builtin_io" owns its extensions before any plugin loads
  const PluginLoadReport r = load_default_plugins();
  for (const auto& e : r.errors) std::cerr << "occseg: warning: " << e << "\n";
}

Runner add_plugins(CLI::App& app) {
  auto files = std::make_shared<std::vector<std::string>>();
  CLI::App* cmd = app.add_subcommand("plugins", "List loaded plugins: stages, readers, writers, parameters");
  cmd->add_option("--load", *files, "Also load this plugin file (repeatable); a failure is an error");
  return [cmd, files]() -> int {
    if (!*cmd) return -1;
    for (const auto& f : *files) load_plugin(f);
    list(std::cout);
    return kOk;
  };
}

}  // namespace occseg::cli
