// Ground truth of a simulated scene, per voxel: which object it belongs to, and the ideal state,
// what a noise-free sensor with a dense fan of rays from the same viewpoints would know.
#pragma once
#include <cstdint>
#include <vector>

#include "occseg/sim/scanner.hpp"
#include "occseg/sim/scene.hpp"

namespace occseg::sim {

struct Truth {
  Dims dims;
  std::vector<std::uint8_t> state;     // occseg::State per voxel, x fastest
  std::vector<std::uint16_t> objects;  // object id whose solid holds the voxel centre, 0: none
};

// The object mask: id of the first shape containing each voxel centre (0: empty space). Solids
// thinner than a voxel may fall between centres; the catalogue keeps every part >= 2 voxels.
std::vector<std::uint16_t> object_mask(const Scene& scene, int threads = 0);

// Ideal state of every voxel (docs/experiments.md, "Ground truth"):
//  - occupied: a noise-free ray from some viewpoint, inside its field of view and max range,
//    meets a solid for the first time inside the voxel. Rays are aimed at a 3 x 3 grid of points
//    (3 x 3 x 3 in full3d and rings; the scan plane only in planar mode) of each voxel the surface may cross;
//  - free: otherwise, when the voxel centre is outside every solid and some viewpoint sees it
//    (in view, within max range, nothing in between);
//  - unknown: everything else (occluded, inside solids, out of view or range).
// In planar mode a viewpoint sees a voxel only from the sensor height of that voxel's layer.
Truth ground_truth(const Scene& scene, const ScanConfig& config);

}  // namespace occseg::sim
