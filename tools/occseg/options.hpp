// Options several subcommands share: the pipeline (--preset, --param, --threads), the input
// (--voxel-size, --bbox, ... for map_input), the report (--json, --quiet, --top) and the
// simulated scenes (`simulate`, `demo`).
#pragma once
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "map_input.hpp"
#include "occseg/params.hpp"
#include "occseg/sim/scanner.hpp"

namespace occseg::cli {

// Checks of numeric option values. CLI11's Range and PositiveNumber let NaN through (every
// comparison with it is false), accept what overflows to infinity only by luck of the bounds,
// and read "010" as octal 8; these refuse NaN, infinities and overflow, and say so in words:
// "--voxel-size: nan is not a positive finite number".
CLI::Validator finite_number();                   // any finite number
CLI::Validator positive_number();                 // finite and > 0
CLI::Validator nonnegative_number();              // finite and >= 0
CLI::Validator number_in(double lo, double hi);   // finite, in [lo, hi]
// A whole number in decimal digits (no sign, no 0x) in [lo, hi]; "010" is ten. A transform
// (Option::transform, not check): it hands CLI11 the number without leading zeros.
CLI::Validator whole_number(unsigned long long lo, unsigned long long hi);

struct PipelineArgs {
  std::string preset = "default";
  std::vector<std::string> params;  // name=value
  int threads = 0;
};
// --preset, --param (repeatable), --threads, and a help footer listing every parameter.
void add_pipeline_options(CLI::App* cmd, PipelineArgs& args);
// The preset, then each --param in order, then --threads; validated. Throws Error(invalid_argument)
// naming the parameter for an unknown name or a bad value.
Params make_params(const PipelineArgs& args);
// Every parameter (built-in and from loaded plugins) with kind, default and range, for --help.
std::string params_help();

struct InputArgs {
  double voxel_size = 0;  // 0: not given
  std::vector<double> bbox, sensor_origin, sensor_orientation;
  double max_range = -1;   // < 0: not given (the value given is positive and finite)
  std::string coarsen;     // empty: not given (max)
};
// --voxel-size, --bbox, --sensor-origin, --sensor-orientation, --max-range, --coarsen.
void add_input_options(CLI::App* cmd, InputArgs& args);
MapInputOptions make_input_options(const InputArgs& args, int threads);

struct ReportArgs {
  bool json = false, quiet = false;
  std::size_t top = 5;
};
// --json, --quiet and (with_top) --top.
void add_report_options(CLI::App* cmd, ReportArgs& args, bool with_top = true);

// A simulated scene's own defaults for the options a command line left unset (`occseg simulate`,
// `occseg demo`): the building is a 20 x 15 x 3 m storey (400 x 300 x 60 voxels of 5 cm) scanned
// by spinning lidars that see across it (rings, 25 m); the other scenes keep the paper's room and
// sensor. An option the command lacks counts as unset.
void apply_scene_defaults(CLI::App& cmd, const std::string& scene, std::vector<std::size_t>& dims, double& voxel_size,
                          std::string& mode, double& max_range);
// The scan mode named by --mode (planar, full3d, rings; the option checks the name).
sim::ScanMode scan_mode(const std::string& name);

}  // namespace occseg::cli
