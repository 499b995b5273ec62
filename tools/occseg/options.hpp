// Options several subcommands share: the pipeline (--preset, --param, --threads), the input
// (--voxel-size, --bbox, ... for map_input) and the report (--json, --quiet, --top).
#pragma once
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "map_input.hpp"
#include "occseg/params.hpp"

namespace occseg::cli {

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
  double max_range = -1;
  std::string coarsen = "max";
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

}  // namespace occseg::cli
