#include "options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "occseg/error.hpp"

namespace occseg::cli {

namespace {

std::string g(double v) {
  char t[64];
  std::snprintf(t, sizeof t, "%g", v);
  return t;
}

// The value as the option will hold it (CLI11's own conversion), then: finite, and ok(v).
CLI::Validator checked_number(const std::string& type, const std::string& what, std::function<bool(double)> ok) {
  return CLI::Validator(
      [what, ok](std::string& in) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(in, v)) return "'" + in + "' is not a number";
        if (std::isnan(v) || std::isinf(v) || !ok(v)) return in + " is not " + what;
        return "";
      },
      type);
}

}  // namespace

CLI::Validator finite_number() {
  return checked_number("NUMBER", "a finite number", [](double) { return true; });
}
CLI::Validator positive_number() {
  return checked_number("POSITIVE", "a positive finite number", [](double v) { return v > 0; });
}
CLI::Validator nonnegative_number() {
  return checked_number("NONNEGATIVE", "a non-negative finite number", [](double v) { return v >= 0; });
}
CLI::Validator number_in(double lo, double hi) {
  return checked_number("NUMBER in [" + g(lo) + ", " + g(hi) + "]",
                        "a finite number in [" + g(lo) + ", " + g(hi) + "]",
                        [lo, hi](double v) { return v >= lo && v <= hi; });
}

CLI::Validator whole_number(unsigned long long lo, unsigned long long hi) {
  const std::string range = std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& in) -> std::string {
        const std::string bad = in + " is not a whole number from " + range;
        if (in.empty() || in.find_first_not_of("0123456789") != std::string::npos) return bad;
        errno = 0;
        const unsigned long long v = std::strtoull(in.c_str(), nullptr, 10);
        if (errno == ERANGE || v < lo || v > hi) return bad;
        // CLI11 would read a leading 0 as octal: hand it the number without them.
        in = std::to_string(v);
        return "";
      },
      "INT in " + range);
}

void add_pipeline_options(CLI::App* c, PipelineArgs& a) {
  c->add_option("--preset", a.preset, "paper (as published) or default (with the safety rules; the default)")
      ->check(CLI::IsMember({"paper", "default"}));
  c->add_option("--param", a.params, "NAME=VALUE: set a pipeline or plugin parameter (repeatable; list below)")
      ->type_name("NAME=VALUE");
  c->add_option("--threads", a.threads, "worker threads, 0 = all cores (results never depend on it)")
      ->transform(whole_number(0, 1024));
  c->footer([] { return params_help(); });
}

Params make_params(const PipelineArgs& a) {
  Params p;
  set_param(p, "preset", a.preset);
  for (const std::string& kv : a.params) {
    const std::size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0)
      throw Error(Status::invalid_argument, "--param '" + kv + "' is not NAME=VALUE");
    set_param(p, kv.substr(0, eq), kv.substr(eq + 1));
  }
  p.threads = a.threads;
  p.validate();
  return p;
}

std::string params_help() {
  std::ostringstream o;
  o << "Parameters for --param NAME=VALUE (defaults of the default preset; docs/algorithm.md):\n";
  for (const ParamInfo& i : all_params()) {
    const std::string owner = param_owner(i.name);
    o << "  " << i.name << " (" << i.kind << ", default " << param_default(i.name);
    if (std::string(i.kind) != "string") o << ", " << i.min << ".." << i.max;
    if (owner != "builtin") o << ", plugin " << owner;
    o << "): " << i.description << "\n";
  }
  return o.str();
}

void add_input_options(CLI::App* c, InputArgs& a) {
  c->add_option("--voxel-size", a.voxel_size,
                "voxel edge in metres (.npy: default 1; .nrrd: the file's spacing; .pcd/.graph: default 0.05; "
                ".bt/.ot: a multiple of the tree resolution, default the resolution)")
      ->check(positive_number());
  c->add_option("--bbox", a.bbox, "grid box XMIN YMIN ZMIN XMAX YMAX ZMAX in metres (.pcd .graph .bt .ot; default: fitted)")
      ->expected(6)
      ->check(finite_number());
  c->add_option("--sensor-origin", a.sensor_origin,
                "X Y Z: sensor position for .pcd/.graph (default: the stored one; the stored orientation is kept)")
      ->expected(3)
      ->check(finite_number());
  c->add_option("--sensor-orientation", a.sensor_orientation,
                "W X Y Z: sensor rotation quaternion for .pcd/.graph (normalised; not all zero; default: the "
                "stored one; the stored position is kept)")
      ->expected(4)
      ->check(finite_number());
  c->add_option("--max-range", a.max_range, "metres; longer returns mark free space only (.pcd/.graph)")
      ->check(positive_number());
  c->add_option("--coarsen", a.coarsen, "max or mean: rule for .bt/.ot at a coarser voxel size")
      ->check(CLI::IsMember({"max", "mean"}));
}

MapInputOptions make_input_options(const InputArgs& a, int threads) {
  MapInputOptions in;
  if (a.voxel_size > 0) in.voxel_size = a.voxel_size;
  if (!a.bbox.empty()) in.bbox = std::array<double, 6>{a.bbox[0], a.bbox[1], a.bbox[2], a.bbox[3], a.bbox[4], a.bbox[5]};
  if (!a.sensor_origin.empty())
    in.sensor_origin = std::array<double, 3>{a.sensor_origin[0], a.sensor_origin[1], a.sensor_origin[2]};
  if (!a.sensor_orientation.empty() && a.sensor_orientation == std::vector<double>{0, 0, 0, 0})
    throw Error(Status::invalid_argument, "--sensor-orientation 0 0 0 0 is no rotation (give W X Y Z, e.g. 1 0 0 0)");
  if (!a.sensor_orientation.empty())
    in.sensor_orientation = std::array<double, 4>{a.sensor_orientation[0], a.sensor_orientation[1],
                                                  a.sensor_orientation[2], a.sensor_orientation[3]};
  in.max_range = a.max_range;
  in.coarsen = a.coarsen;  // empty: not given
  in.threads = threads;
  return in;
}

void add_report_options(CLI::App* c, ReportArgs& a, bool with_top) {
  c->add_flag("--json", a.json, "print a machine-readable JSON summary on stdout instead of the text");
  c->add_flag("--quiet,-q", a.quiet, "no text summary and no progress bar (errors still go to stderr)");
  if (with_top)
    c->add_option("--top", a.top, "number of largest objects listed in the summary (default 5)")
        ->transform(whole_number(0, 1000000));
}

void apply_scene_defaults(CLI::App& cmd, const std::string& scene, std::vector<std::size_t>& dims, double& voxel_size,
                          std::string& mode, double& max_range) {
  if (scene != "building") return;
  const auto unset = [&](const char* name) {
    const CLI::Option* o = cmd.get_option_no_throw(name);
    return !o || o->count() == 0;
  };
  if (unset("--dims")) dims = {400, 300, 60};
  if (unset("--voxel-size")) voxel_size = 0.05;
  if (unset("--mode")) mode = "rings";
  if (unset("--max-range")) max_range = 25.0;
}

sim::ScanMode scan_mode(const std::string& name) {
  return name == "full3d" ? sim::ScanMode::full3d : name == "rings" ? sim::ScanMode::rings : sim::ScanMode::planar;
}

}  // namespace occseg::cli
