// The naive baseline of the experiments: per-voxel thresholds and connected components
// (baseline.hpp).
#include "occseg/sim/baseline.hpp"

#include <chrono>

#include "rules/objects.hpp"
#include "stages/label.hpp"

namespace occseg::sim {

Result threshold_segmentation(const Grid& grid, const Params& params) {
  params.validate();
  check_probabilities(grid);
  Result r;
  r.dims = grid.dims;
  r.voxel_size = grid.voxel_size;
  r.origin = grid.origin;
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::uint8_t> states(grid.p.size());
  for (std::size_t i = 0; i < states.size(); ++i) states[i] = static_cast<std::uint8_t>(params.state_of(grid.p[i]));
  auto t1 = std::chrono::steady_clock::now();
  label_components(states, grid, r.labels, r.segments);
  assign_kinds(r.segments, params, grid.dims);
  auto t2 = std::chrono::steady_clock::now();
  r.timings.push_back({"thresholding", std::chrono::duration<double>(t1 - t0).count()});
  r.timings.push_back({"labelling", std::chrono::duration<double>(t2 - t1).count()});
  return r;
}

}  // namespace occseg::sim
