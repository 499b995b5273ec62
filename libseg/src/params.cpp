#include "occseg/params.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "occseg/error.hpp"

namespace occseg {

const char* state_name(State s) {
  switch (s) {
    case State::free: return "free";
    case State::unknown: return "unknown";
    case State::occupied: return "occupied";
  }
  return "?";
}

const char* preset_name(Preset p) { return p == Preset::paper ? "paper" : "default"; }

Params Params::paper() {
  Params p;
  p.preset = Preset::paper;
  return p;
}

Params Params::defaults() { return Params(); }

const std::vector<ParamInfo>& param_table() {
  static const std::vector<ParamInfo> t = {
      {"preset", "string", 0, 0, "paper (as published) or default (paper plus per-voxel safety rules); setting it resets all others"},
      {"smax", "int", 2, 4096, "edge of the first blocks of the hierarchical division, voxels (power of two)"},
      {"smin", "int", 1, 4096, "edge of the smallest blocks, voxels (power of two, <= smax)"},
      {"split_ratio", "double", 1.0, 1e9, "X of eq. (2): a block splits while Gmax / Gmin > X"},
      {"contrast_bins", "int", 2, 64, "b: contrast levels of the 64 x b LBP/C histograms"},
      {"free_below", "double", 0.0, 1.0, "a mean or voxel probability below this is free"},
      {"occupied_above", "double", 0.0, 1.0, "a mean or voxel probability above this is occupied"},
      {"lookahead", "int", 1, 64, "voxels examined beyond a free/occupied boundary in refinement"},
      {"refine_passes", "int", 0, 16, "passes of the six free/occupied refinement scans"},
      {"gap_radius", "int", 0, 16, "default preset: 0.5-voxels holding no (2r+1)^3 cube of 0.5 are gaps between rays"},
      {"threads", "int", 0, 1024, "worker threads, 0 = all cores; results never depend on it"},
  };
  return t;
}

namespace {

bool is_pow2(int v) { return v > 0 && (v & (v - 1)) == 0; }

const ParamInfo* find_info(const std::string& name) {
  for (const auto& i : param_table())
    if (name == i.name) return &i;
  return nullptr;
}

[[noreturn]] void bad(const std::string& name, const std::string& why) {
  throw Error(Status::invalid_argument, "parameter '" + name + "': " + why);
}

double parse_number(const ParamInfo& info, const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s, &end);
  if (text.empty() || end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v))
    bad(info.name, "'" + text + "' is not a number");
  if (std::string(info.kind) == "int" && v != std::floor(v)) bad(info.name, "'" + text + "' is not an integer");
  if (v < info.min || v > info.max) {
    std::ostringstream o;
    o << text << " is outside [" << info.min << ", " << info.max << "]";
    bad(info.name, o.str());
  }
  return v;
}

}  // namespace

void Params::validate() const {
  auto check = [](const char* name, double v) {
    const ParamInfo* info = find_info(name);
    if (!(v >= info->min && v <= info->max)) {
      std::ostringstream o;
      o << v << " is outside [" << info->min << ", " << info->max << "]";
      bad(name, o.str());
    }
  };
  check("smax", smax);
  check("smin", smin);
  check("split_ratio", split_ratio);
  check("contrast_bins", contrast_bins);
  check("free_below", free_below);
  check("occupied_above", occupied_above);
  check("lookahead", lookahead);
  check("refine_passes", refine_passes);
  check("gap_radius", gap_radius);
  check("threads", threads);
  if (!is_pow2(smax)) bad("smax", std::to_string(smax) + " is not a power of two");
  if (!is_pow2(smin)) bad("smin", std::to_string(smin) + " is not a power of two");
  if (smin > smax) bad("smin", std::to_string(smin) + " is larger than smax = " + std::to_string(smax));
  if (free_below > occupied_above) bad("free_below", "is above occupied_above");
}

void set_param(Params& p, const std::string& name, const std::string& value) {
  if (name == "preset") {
    if (value == "paper") p = Params::paper();
    else if (value == "default") p = Params::defaults();
    else bad(name, "'" + value + "' is not a preset (paper, default)");
    return;
  }
  const ParamInfo* info = find_info(name);
  if (!info) bad(name, "no such parameter");
  const double v = parse_number(*info, value);
  if (name == "smax") p.smax = static_cast<int>(v);
  else if (name == "smin") p.smin = static_cast<int>(v);
  else if (name == "split_ratio") p.split_ratio = v;
  else if (name == "contrast_bins") p.contrast_bins = static_cast<int>(v);
  else if (name == "free_below") p.free_below = v;
  else if (name == "occupied_above") p.occupied_above = v;
  else if (name == "lookahead") p.lookahead = static_cast<int>(v);
  else if (name == "refine_passes") p.refine_passes = static_cast<int>(v);
  else if (name == "gap_radius") p.gap_radius = static_cast<int>(v);
  else if (name == "threads") p.threads = static_cast<int>(v);
}

std::string get_param(const Params& p, const std::string& name) {
  std::ostringstream o;
  o.precision(17);
  if (name == "preset") o << preset_name(p.preset);
  else if (name == "smax") o << p.smax;
  else if (name == "smin") o << p.smin;
  else if (name == "split_ratio") o << p.split_ratio;
  else if (name == "contrast_bins") o << p.contrast_bins;
  else if (name == "free_below") o << p.free_below;
  else if (name == "occupied_above") o << p.occupied_above;
  else if (name == "lookahead") o << p.lookahead;
  else if (name == "refine_passes") o << p.refine_passes;
  else if (name == "gap_radius") o << p.gap_radius;
  else if (name == "threads") o << p.threads;
  else bad(name, "no such parameter");
  return o.str();
}

}  // namespace occseg
