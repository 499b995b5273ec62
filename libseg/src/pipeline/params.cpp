// occseg::Params: the presets, validation, and parameters by name (params.hpp).
#include "occseg/params.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "occseg/error.hpp"
#include "occseg/registry.hpp"
#include "occseg/result.hpp"
#include "registry/registry_internal.hpp"

namespace occseg {

const char* state_name(State s) {
  switch (s) {
    case State::free: return "free";
    case State::unknown: return "unknown";
    case State::occupied: return "occupied";
  }
  return "?";
}

const char* kind_name(Kind k) {
  switch (k) {
    case Kind::free: return "free";
    case Kind::unknown: return "unknown";
    case Kind::structure: return "structure";
    case Kind::object: return "object";
    case Kind::clutter: return "clutter";
  }
  return "?";
}

const char* preset_name(Preset p) { return p == Preset::paper ? "paper" : "default"; }

Params Params::paper() {
  Params p;
  p.preset = Preset::paper;
  p.occupied_connectivity = 6;
  p.support_plane = 0;
  p.object_gap = 0;
  p.min_object_voxels = 0;
  p.min_pocket_voxels = 0;
  p.surface_band = 0;
  p.structure_planes = 0;
  p.plane_holes = 0;
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
      {"occupied_connectivity", "int", 6, 26, "6 or 26: neighbours that join occupied voxels into one segment (default 26, paper 6)"},
      {"support_plane", "int", 0, 1e9, "default preset: voxels of a plane (>= half its segment) that splits objects standing on it off their support; 0 = off"},
      {"object_gap", "int", 0, 16, "default preset: occupied segments joined by a path of at most this many unknown voxels are one object; 0 = off"},
      {"min_object_voxels", "int", 0, 1e9, "default preset: occupied groups smaller than this join an object within object_gap + 1 voxels, else are clutter; 0 = off"},
      {"min_pocket_voxels", "int", 0, 1e9, "default preset: free regions smaller than this (not the main free space) become unknown, unknown ones this small next to an object join it; 0 = off"},
      {"surface_band", "int", 0, 16, "default preset: free voxels in thin free space within this many face steps of an occupied and of an unknown voxel become occupied (the noisy band inside a surface); 0 = off"},
      {"structure_planes", "int", 0, 256, "default preset: planes searched per occupied segment; those spanning structure_extent both ways are structure (floor, walls, ceiling), what stands on or against them objects; 0 = off"},
      {"structure_extent", "double", 0.001, 1e6, "default preset: metres a plane must span in both of its directions to be structure (rule 11)"},
      {"plane_holes", "int", 0, 16, "default preset: free runs of at most this many voxels along a plane piece's in-plane axes, inside its extent and between non-free voxels of its band, become occupied (rule 12); 0 = off"},
      {"threads", "int", 0, 1024, "worker threads, 0 = all cores; results never depend on it"},
      {"texture", "string", 0, 0, "texture operator by name: auto (lbp8 when nz = 1, else lbp6), lbp6 (paper, 3D), lbp8 (3x3, 2D maps) or one a plugin adds"},
      {"similarity", "string", 0, 0, "histogram similarity of the division by name: g (eq. 1), chi2 or one a plugin adds"},
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

void check_stage_names(const Params& p) {
  if (p.texture != "auto" && !find_texture(p.texture))
    throw Error(Status::invalid_argument, "parameter 'texture': '" + p.texture +
                                              "' is not a registered texture operator (registered: " + texture_names() + ")");
  if (!find_similarity(p.similarity))
    throw Error(Status::invalid_argument, "parameter 'similarity': '" + p.similarity +
                                              "' is not a registered similarity (registered: " + similarity_names() + ")");
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

std::string resolved_texture(const Params& p, const Dims& d) {
  if (p.texture != "auto") return p.texture;
  return d.nz == 1 ? "lbp8" : "lbp6";
}

double check_param_value(const ParamInfo& info, const std::string& text) {
  return std::string(info.kind) == "string" ? 0.0 : parse_number(info, text);
}

std::vector<ParamInfo> all_params() {
  std::vector<ParamInfo> v = param_table();
  for (const PluginParam* p : plugin_params()) v.push_back(p->info);
  return v;
}

const ParamInfo* find_param(const std::string& name) {
  if (const ParamInfo* i = find_info(name)) return i;
  const PluginParam* p = find_plugin_param(name);
  return p ? &p->info : nullptr;
}

std::string param_default(const std::string& name) {
  if (find_info(name)) return get_param(Params::defaults(), name);
  const PluginParam* p = find_plugin_param(name);
  if (!p) bad(name, "no such parameter");
  return p->default_value;
}

std::string param_owner(const std::string& name) {
  if (find_info(name)) return kBuiltinPlugin;
  const PluginParam* p = find_plugin_param(name);
  if (!p) bad(name, "no such parameter");
  return p->plugin;
}

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
  check("occupied_connectivity", occupied_connectivity);
  if (occupied_connectivity != 6 && occupied_connectivity != 26)
    bad("occupied_connectivity", std::to_string(occupied_connectivity) + " is neither 6 nor 26");
  check("support_plane", support_plane);
  check("object_gap", object_gap);
  check("min_object_voxels", min_object_voxels);
  check("min_pocket_voxels", min_pocket_voxels);
  check("surface_band", surface_band);
  check("structure_planes", structure_planes);
  check("structure_extent", structure_extent);
  check("plane_holes", plane_holes);
  check("threads", threads);
  if (!is_pow2(smax)) bad("smax", std::to_string(smax) + " is not a power of two");
  if (!is_pow2(smin)) bad("smin", std::to_string(smin) + " is not a power of two");
  if (smin > smax) bad("smin", std::to_string(smin) + " is larger than smax = " + std::to_string(smax));
  if (free_below > occupied_above) bad("free_below", "is above occupied_above");
  check_stage_names(*this);
  for (const auto& kv : plugin_values)
    if (!find_plugin_param(kv.first)) bad(kv.first, "no such parameter");
}

void set_param(Params& p, const std::string& name, const std::string& value) {
  if (name == "preset") {
    if (value == "paper") p = Params::paper();
    else if (value == "default") p = Params::defaults();
    else bad(name, "'" + value + "' is not a preset (paper, default)");
    return;
  }
  if (name == "texture" || name == "similarity") {
    Params q = p;
    (name == "texture" ? q.texture : q.similarity) = value;
    check_stage_names(q);
    p = std::move(q);
    return;
  }
  const ParamInfo* info = find_info(name);
  if (!info) {
    const PluginParam* pp = find_plugin_param(name);
    if (!pp) bad(name, "no such parameter");
    check_param_value(pp->info, value);
    p.plugin_values[name] = value;
    return;
  }
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
  else if (name == "occupied_connectivity") p.occupied_connectivity = static_cast<int>(v);
  else if (name == "support_plane") p.support_plane = static_cast<int>(v);
  else if (name == "object_gap") p.object_gap = static_cast<int>(v);
  else if (name == "min_object_voxels") p.min_object_voxels = static_cast<int>(v);
  else if (name == "min_pocket_voxels") p.min_pocket_voxels = static_cast<int>(v);
  else if (name == "surface_band") p.surface_band = static_cast<int>(v);
  else if (name == "structure_planes") p.structure_planes = static_cast<int>(v);
  else if (name == "plane_holes") p.plane_holes = static_cast<int>(v);
  else if (name == "structure_extent") p.structure_extent = v;
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
  else if (name == "occupied_connectivity") o << p.occupied_connectivity;
  else if (name == "support_plane") o << p.support_plane;
  else if (name == "object_gap") o << p.object_gap;
  else if (name == "min_object_voxels") o << p.min_object_voxels;
  else if (name == "min_pocket_voxels") o << p.min_pocket_voxels;
  else if (name == "surface_band") o << p.surface_band;
  else if (name == "structure_planes") o << p.structure_planes;
  else if (name == "plane_holes") o << p.plane_holes;
  else if (name == "structure_extent") o << p.structure_extent;
  else if (name == "threads") o << p.threads;
  else if (name == "texture") o << p.texture;
  else if (name == "similarity") o << p.similarity;
  else if (const PluginParam* pp = find_plugin_param(name)) {
    const auto it = p.plugin_values.find(name);
    o << (it != p.plugin_values.end() ? it->second : pp->default_value);
  } else bad(name, "no such parameter");
  return o.str();
}

}  // namespace occseg
