// occseg::Params: every setting of the pipeline, with the paper's values as defaults, and the
// two presets. Parameters are also reachable by name (set_param), so the C ABI, the command line
// and the Python bindings share one table instead of three switch statements.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "occseg/grid.hpp"

namespace occseg {

enum class State : std::uint8_t { free = 0, unknown = 1, occupied = 2 };
const char* state_name(State s);

enum class Preset { paper, default_preset };

struct Params {
  Preset preset = Preset::default_preset;
  int smax = 64;               // size of the first blocks (voxels per edge)
  int smin = 8;                // smallest block size
  double split_ratio = 1.2;    // X of eq. (2): split while Gmax / Gmin > X
  int contrast_bins = 8;       // b: histograms have 64 x b bins
  double free_below = 0.498;   // p < free_below: free
  double occupied_above = 0.502;  // p > occupied_above: occupied; in between: unknown
  int lookahead = 3;           // voxels examined beyond a free/occupied boundary in refinement
  int refine_passes = 2;       // passes of the six free/occupied scans
  // default preset only: 0.5-valued regions that hold no (2r+1)^3 cube of them (r = gap_radius; 0: none) are "gaps between
  // rays" and take the state of the texture segmentation around them; thicker ones stay unknown.
  int gap_radius = 1;
  // Connectivity of occupied segments: 26 (default preset: voxels touching at an edge or a corner
  // are one object, so thin sloping shells stay whole) or 6 (paper). Free and unknown: always 6.
  int occupied_connectivity = 26;
  // default preset only: an occupied segment lying at least half on one plane of at least this
  // many voxels (a table top, a floor) splits into the plane and the objects standing on its
  // observed side (occseg/planes.hpp). 0: off (paper).
  int support_plane = 256;
  // default preset only (rules/objects.hpp; 0: off, as in the paper preset): occupied segments
  // joined by a 6-connected path of at most object_gap unknown voxels are one object (a surface
  // scanned in rings with unknown between them); occupied groups of fewer than min_object_voxels
  // join an object within object_gap + 1 voxels or are clutter; free regions of fewer than
  // min_pocket_voxels (not the main free space) become unknown, and unknown ones that small next
  // to an object join it.
  int object_gap = 4;
  int min_object_voxels = 64;
  int min_pocket_voxels = 64;
  // default preset only (rules/surface_band.hpp; 0: off, as in the paper preset): a free voxel in
  // thin free space (no 3 x 3 x 3 cube of free voxels holds it) within surface_band face steps of
  // an occupied voxel and of an unknown one becomes occupied: the band of free voxels the range
  // noise leaves just inside an object's surface goes to the object.
  int surface_band = 2;
  // default preset only (rules/structure.hpp; 0: off, as in the paper preset): up to
  // structure_planes planes are searched in each occupied segment that no single support plane
  // holds half of; a plane whose voxels (at least support_plane of them) span structure_extent
  // metres both ways is structure (a floor, a wall, a ceiling), and what stands on or against it
  // is split off as objects. Small occupied groups lying in a plane of a larger segment, inside
  // its extent, join it (a table top seen edge-on in pieces).
  int structure_planes = 32;
  double structure_extent = 2.0;
  // default preset only (rules/plane_holes.hpp; 0: off, as in the paper preset): a free voxel in
  // the inlier band of a plane piece found by rule 11, inside its extent, whose run of free voxels
  // along one of the plane's in-plane axes is at most plane_holes voxels long and ends at a
  // non-free voxel of the band on both sides (one of them occupied), becomes occupied: rays that
  // graze a thin surface seen edge-on cross it; a door or a window is a larger hole and stays free.
  int plane_holes = 4;
  int threads = 0;             // 0: all cores. Results never depend on it.
  // Texture operator, by name (occseg/registry.hpp). "auto" (both presets): lbp8, the authors'
  // 2D operator, on a one-layer map (nz = 1), lbp6 on any other (resolved_texture).
  std::string texture = "auto";
  std::string similarity = "g";     // histogram similarity of the division, by name
  // Values of parameters that plugins declared, as text, by name; unset ones take the declared
  // default (get_param).
  std::map<std::string, std::string> plugin_values;
  // Called between stages and inside long ones with a stage name and a fraction in [0, 1].
  // Returning false cancels: segment() throws Error(cancelled).
  std::function<bool(const char* stage, double fraction)> progress;

  static Params paper();
  static Params defaults();

  State state_of(double p) const {
    return p < free_below ? State::free : (p > occupied_above ? State::occupied : State::unknown);
  }
  // "p equals 0.5" for refinement: p lies in the unknown band (see docs/algorithm.md).
  bool at_half(double p) const { return p >= free_below && p <= occupied_above; }

  // Throws Error(invalid_argument) naming the parameter when a value is out of its bounds or
  // the combination is inconsistent (smin > smax, free_below > occupied_above, ...), or when
  // texture / similarity name no registered stage.
  void validate() const;
};

// The texture operator a segmentation of a map of `dims` uses: params.texture, or for "auto"
// "lbp8" when dims.nz == 1 and "lbp6" otherwise.
std::string resolved_texture(const Params& params, const Dims& dims);

// Description of one named parameter, for --help, occseg_params_* and the Python bindings.
struct ParamInfo {
  const char* name;
  const char* kind;     // "int", "double" or "string"
  double min, max;      // bounds for numbers
  const char* description;
};
// The built-in parameters (those of this struct), in a fixed order.
const std::vector<ParamInfo>& param_table();
// Every parameter known now: param_table() followed by those plugins declared, in load order.
std::vector<ParamInfo> all_params();
// A parameter by name, built-in or declared by a plugin; nullptr when unknown. The pointer stays
// valid for the life of the process.
const ParamInfo* find_param(const std::string& name);
// The default value of a parameter as text (the default preset's for built-in ones), and the
// plugin that declared it ("builtin" for the core's own). Throw for unknown names.
std::string param_default(const std::string& name);
std::string param_owner(const std::string& name);

// Sets one parameter by name from text ("smax", "64"); "preset" resets everything to the named
// preset. Parameters declared by loaded plugins are set the same way. Throws
// Error(invalid_argument) naming the parameter for unknown names or bad values (a texture or
// similarity name that is not registered is a bad value).
void set_param(Params& params, const std::string& name, const std::string& value);
// The current value of a named parameter as text; throws for unknown names.
std::string get_param(const Params& params, const std::string& name);

const char* preset_name(Preset p);

}  // namespace occseg
