// Probabilistic fusion of range scans into an occupancy grid (log-odds inverse sensor model, as
// OctoMap). One implementation serves the simulator, the PCL adapter and OctoMap scan graphs.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "occseg/grid.hpp"

namespace occseg {

using Vec3 = std::array<double, 3>;

// OctoMap's default inverse sensor model.
struct SensorModel {
  double p_hit = 0.7;        // probability that a voxel holding a return is occupied
  double p_miss = 0.4;       // probability for a voxel a ray passed through
  double clamp_min = 0.12;   // probabilities are clamped to [clamp_min, clamp_max]
  double clamp_max = 0.97;
  double max_range = -1;     // metres; < 0: unlimited. Longer rays mark free space only.
  // Throws Error(invalid_argument) naming the field when a value is out of range.
  void validate() const;
};

// A box of voxels in world coordinates: `origin` is the world position of the corner of voxel
// (0, 0, 0), voxels are cubes of edge `voxel_size` metres.
struct GridFrame {
  Dims dims;
  double voxel_size = 0.05;
  Vec3 origin{0, 0, 0};
};

// Accumulates scans. Every voxel starts at log-odds 0 (p = 0.5 exactly) and stays there until
// a ray touches it. Within one scan a voxel is updated at most once, and a hit wins over a miss
// (OctoMap's insertPointCloud semantics), so results do not depend on ray order or threads.
class OccupancyFusion {
 public:
  OccupancyFusion(const GridFrame& frame, const SensorModel& model = SensorModel());

  // Inserts one scan: rays from `sensor` (world metres) to each endpoint. Endpoints with a NaN
  // or infinite coordinate are skipped. Rays are clipped to the grid box; the endpoint voxel gets
  // a hit when the endpoint lies inside the grid and within max_range; every other voxel the
  // ray crosses gets a miss.
  void insert_scan(const Vec3& sensor, const std::vector<Vec3>& endpoints, int threads = 0);
  // Same, from a flat array of xyz floats with a given stride in floats (e.g. PCL's 4-float
  // points), so adapters need not copy clouds.
  void insert_scan(const Vec3& sensor, const float* xyz, std::size_t count, std::size_t stride_floats,
                   int threads = 0);

  // Progress of insert_scan, for long scans: called from the calling thread after each chunk
  // of rays with the rays of the current scan traced so far and the scan's point count.
  // Returning false cancels: insert_scan throws Error(cancelled) before touching the grid, which
  // keeps the scans inserted earlier. An empty function (the default) reports nothing.
  using Progress = std::function<bool(std::size_t done, std::size_t count)>;
  void set_progress(Progress progress) { progress_ = std::move(progress); }

  const GridFrame& frame() const { return frame_; }
  const std::vector<float>& log_odds() const { return log_odds_; }
  // The occupancy probabilities; untouched voxels are exactly 0.5.
  Grid grid() const;
  // Number of scans and rays inserted so far.
  std::uint64_t scans() const { return scans_; }
  std::uint64_t rays() const { return rays_; }

 private:
  GridFrame frame_;
  SensorModel model_;
  float l_hit_, l_miss_, l_min_, l_max_;
  std::vector<float> log_odds_;
  std::vector<std::uint8_t> marks_;  // per scan: 1 crossed, 2 hit; all zero between scans
  std::uint64_t scans_ = 0, rays_ = 0;
  Progress progress_;
};

// The voxel that OccupancyFusion::insert_scan over `frame` gives the hit of a return at `end`
// seen from `sensor` (both world metres, as insert_scan takes them): the same arithmetic as the
// ray walk, so a point's voxel here is always the voxel its return went into. Ignores max range
// (a return beyond it still lies in that voxel). False, and `index` untouched, when `end` is not
// finite or lies outside the grid box; `sensor` must be finite. index = x + nx * (y + ny * z).
bool endpoint_voxel(const GridFrame& frame, const Vec3& sensor, const float end[3], std::uint64_t& index);

// The frame (origin and dims) of the smallest voxel-aligned box that holds all the points and
// the sensor positions, padded by `margin` metres.
GridFrame fit_frame(const std::vector<Vec3>& points, double voxel_size, double margin = 0.0);

}  // namespace occseg
