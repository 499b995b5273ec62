// The laser range finder of section 4: Gaussian range noise, a fixed angular step, several points
// of view, and the probabilistic map built from its scans with occseg::OccupancyFusion.
//
// Two constructions:
//  - planar (the paper's): a planar scanner sweeps one horizontal fan per layer, at the height of
//    the layer's voxel centres; each layer is fused as a 2D map and the 128 layers are stacked.
//  - full3d: a 3D scanner at each viewpoint sweeps azimuth and pitch with the same step; all scans
//    are fused into one 3D grid.
//  - rings: a spinning multi-beam 3D lidar: one ring of rays per beam, the beams `ring_step_deg`
//    apart in pitch (3 degrees: 31 rings over the default -45..45, an Ouster OS0-32's spacing) and
//    the rays of a ring `angle_step_deg` apart in azimuth; fused as full3d. A wall 5 m away gets
//    a ring of returns every 26 cm, with unknown voxels between them, as in real building maps.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "occseg/fusion.hpp"
#include "occseg/grid.hpp"
#include "occseg/sim/random.hpp"
#include "occseg/sim/scene.hpp"

namespace occseg::sim {

enum class ScanMode { planar, full3d, rings };
const char* scan_mode_name(ScanMode m);

struct ScanConfig {
  ScanMode mode = ScanMode::planar;
  double range_sigma = 0.04;    // metres, standard deviation of the range error
  double angle_step_deg = 0.5;  // between adjacent rays (and adjacent pitch rows in full3d)
  double ring_step_deg = 3.0;   // rings mode: between adjacent rings (beams) in pitch
  double max_range = 8.0;       // metres: farther surfaces give no return (free space only)
  std::uint64_t seed = 1;
  SensorModel model;            // inverse sensor model of the fusion (OctoMap's defaults)
  int threads = 0;              // 0: all cores; the map never depends on it
  // simulate_map reports the share of the work done, in [0, 1] (layers in planar mode, rays in
  // full3d and rings), one call at a time, possibly from a worker thread; returning false cancels:
  // simulate_map throws Error(cancelled).
  std::function<bool(double fraction)> progress;
  // Throws Error(invalid_argument) naming the field when a value is out of range.
  void validate() const;
};

// Unit ray directions of one scan from `v`, in a fixed order: azimuth from heading - fov/2 up in
// steps of `step_deg` (a 360 degree fan does not repeat its first ray); in full3d, one such row
// per pitch from pitch_min up to pitch_max; in rings, one row per pitch from pitch_min up to
// pitch_max in steps of `ring_step_deg`.
std::vector<Vec3> ray_directions(const Viewpoint& v, ScanMode mode, double step_deg, double ring_step_deg = 3.0);

// True when unit direction d lies in the viewpoint's field of view (the set ray_directions
// samples, rings included: the ground truth is what a dense fan would see): azimuth within fov/2
// of the heading and, in full3d and rings, pitch within the pitch range;
// in planar mode d must be horizontal.
bool in_view(const Viewpoint& v, ScanMode mode, const Vec3& d);

// One measurement along unit direction d from o: the true range to the first solid plus
// N(0, sigma) noise (clamped at 0), or NaN when no solid lies within max_range.
double measure_range(const Scene& scene, const Vec3& o, const Vec3& d, const ScanConfig& config, Rng& rng);

// The end points of one scan. A ray without return ends at 2 * max_range, which the fusion
// (whose max_range is config.max_range) turns into free space along max_range and no hit.
std::vector<Vec3> scan_endpoints(const Scene& scene, const Vec3& sensor, const std::vector<Vec3>& directions,
                                 const ScanConfig& config, Rng& rng);

// The sensor position of viewpoint `v` for layer `z` in planar mode (height of the layer's voxel
// centres) or its own position in full3d and rings (z ignored).
Vec3 sensor_position(const Scene& scene, const Viewpoint& v, ScanMode mode, std::size_t z);

// Simulates all scans and fuses them: the probabilistic map. Scan k of layer z (planar) or
// viewpoint k (full3d, rings) draws its noise from Rng(mix_seed(seed, z, k)), so the map depends only on
// the scene and the config, not on the thread count. Never-observed voxels are exactly 0.5.
Grid simulate_map(const Scene& scene, const ScanConfig& config);

}  // namespace occseg::sim
