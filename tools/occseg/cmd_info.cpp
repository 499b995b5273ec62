// `occseg info FILE`: describes a map file without segmenting it: format, dims, voxel size,
// origin and extent, value range, voxels per state (by the thresholds of the preset and
// --param), never-observed voxels. Clouds are fused first, with the same options as `segment`.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "occseg/error.hpp"
#include "map_input.hpp"
#include "options.hpp"
#include "progress.hpp"

namespace occseg::cli {

namespace {

struct InfoArgs {
  std::string input;
  PipelineArgs pipeline;
  InputArgs in;
  ReportArgs report;
};

struct Stats {
  double min = 1, max = 0, mean = 0;
  std::array<std::uint64_t, 3> states{};
  std::uint64_t unobserved = 0;  // exactly 0.5: never touched by a sensor
};

Stats stats_of(const Grid& g, const Params& p) {
  Stats s;
  double sum = 0;
  for (float v : g.p) {
    s.min = std::min(s.min, double(v));
    s.max = std::max(s.max, double(v));
    sum += v;
    ++s.states[static_cast<int>(p.state_of(v))];
    s.unobserved += v == 0.5f;
  }
  s.mean = g.p.empty() ? 0 : sum / double(g.p.size());
  return s;
}

std::string g6(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

std::string vec(const std::array<double, 3>& v) { return "(" + g6(v[0]) + ", " + g6(v[1]) + ", " + g6(v[2]) + ")"; }

int run(const InfoArgs& o) {
  install_interrupt_handlers();  // Ctrl-C cancels through the progress callbacks
  const Params params = make_params(o.pipeline);
  ProgressBar bar(stderr_is_terminal() && !o.report.quiet);
  MapInputOptions in = make_input_options(o.in, o.pipeline.threads);
  in.progress = bar.callback("fusing scans");
  const auto t = std::chrono::steady_clock::now();
  const MapInput input = load_map(o.input, in);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  check_interrupted();
  bar.clear();
  const Grid& g = input.grid;
  const Stats s = stats_of(g, params);
  const Dims& d = g.dims;
  std::array<double, 3> hi{};
  for (int k = 0; k < 3; ++k) hi[k] = g.origin[k] + double(k == 0 ? d.nx : k == 1 ? d.ny : d.nz) * g.voxel_size;
  const double n = double(d.count());
  if (o.report.json) {
    const nlohmann::json j{{"file", o.input},
                           {"format", input.format},
                           {"dims", {d.nx, d.ny, d.nz}},
                           {"voxels", d.count()},
                           {"voxel_size", g.voxel_size},
                           {"origin", g.origin},
                           {"extent_m", {{"min", g.origin}, {"max", hi}}},
                           {"values", {{"min", s.min}, {"max", s.max}, {"mean", s.mean}}},
                           {"thresholds", {{"free_below", params.free_below}, {"occupied_above", params.occupied_above}}},
                           {"states", {{"free", s.states[0]}, {"unknown", s.states[1]}, {"occupied", s.states[2]}}},
                           {"unobserved", s.unobserved},
                           {"read_seconds", seconds}};
    std::cout << j.dump(1) << "\n";
    return kOk;
  }
  if (o.report.quiet) return kOk;
  auto share = [&](std::uint64_t c) {
    char b[64];
    std::snprintf(b, sizeof b, "%llu (%.2f %%)", static_cast<unsigned long long>(c), 100.0 * double(c) / n);
    return std::string(b);
  };
  std::cout << "file:        " << o.input << "\n"
            << "format:      " << input.format << "\n"
            << "dims:        " << d.nx << " x " << d.ny << " x " << d.nz << " voxels (x, y, z), " << d.count()
            << " in all\n"
            << "voxel size:  " << g6(g.voxel_size) << " m\n"
            << "origin:      " << vec(g.origin) << " m (corner of voxel (0, 0, 0))\n"
            << "extent:      " << vec(g.origin) << " to " << vec(hi) << " m\n"
            << "values:      min " << g6(s.min) << ", max " << g6(s.max) << ", mean " << g6(s.mean) << "\n"
            << "states:      free " << share(s.states[0]) << ", unknown " << share(s.states[1]) << ", occupied "
            << share(s.states[2]) << "  (free p < " << g6(params.free_below) << ", occupied p > "
            << g6(params.occupied_above) << ")\n"
            << "unobserved:  " << share(s.unobserved) << " exactly 0.5\n";
  return kOk;
}

}  // namespace

Runner add_info(CLI::App& app) {
  auto o = std::make_shared<InfoArgs>();
  CLI::App* c = app.add_subcommand("info", "Describe a map file (format, dims, voxel size, values, states) without segmenting it");
  c->add_option("input", o->input, "map file: .npy .nrrd .yaml .pcd .graph .bt .ot (or a plugin's format)")->required();
  add_pipeline_options(c, o->pipeline);  // the state thresholds come from the preset and --param
  add_input_options(c, o->in);
  add_report_options(c, o->report, false);
  return [c, o]() -> int { return c->parsed() ? run(*o) : -1; };
}

}  // namespace occseg::cli
