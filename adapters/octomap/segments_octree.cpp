// segments.ot: occupied segments as a ColorOcTree (occseg/octomap_segments.hpp).
#include <algorithm>
#include <cmath>
#include <string>

#include "occseg/error.hpp"
#include "occseg/octomap_tree.hpp"
#include "occseg/segment_colour.hpp"

namespace occseg {

std::unique_ptr<octomap::ColorOcTree> segments_octree(const Grid& grid, const Result& result,
                                                      OctreePlacement* placement) {
  if (!(result.dims == grid.dims) || result.labels.size() != grid.p.size())
    throw Error(Status::invalid_argument, "the result's dims do not match the map's");
  const double v = grid.voxel_size;
  auto tree = std::make_unique<octomap::ColorOcTree>(v);
  const long centre = long(1) << (tree->getTreeDepth() - 1);  // OctoMap's tree_max_val: key of coordinate 0
  const double keys = double(2 * centre);
  // The lattice position of voxel (0, 0, 0) in voxels, and the shift that puts it there.
  OctreePlacement place;
  long first[3];
  const std::size_t n[3] = {grid.dims.nx, grid.dims.ny, grid.dims.nz};
  for (int k = 0; k < 3; ++k) {
    const double steps = grid.origin[k] / v;
    const double m = std::round(steps);
    // Keys are 16 bits: the map's voxels must have keys in [0, 65535] on every axis.
    if (!(std::fabs(m) <= keys) || m + double(centre) < 0 || m + double(centre) + double(n[k]) > keys)
      throw Error(Status::bad_value,
                  std::string("the map does not fit an OctoMap tree of ") + std::to_string(v) + " m voxels: axis " +
                      std::string(1, "xyz"[k]) + " spans voxels " + std::to_string(m) + " to " +
                      std::to_string(m + double(n[k])) + " from the world origin, beyond the 2^16 keys of OctoMap");
    if (std::fabs(steps - m) > 1e-6) {
      place.snapped = true;
      place.shift[k] = (m - steps) * v;
    }
    first[k] = static_cast<long>(m) + centre;
  }
  // OctoMap's value of one hit (its default prob_hit): every stored voxel counts as occupied.
  const float floor_logodds = octomap::logodds(0.7);
  std::size_t i = 0;
  for (std::size_t z = 0; z < n[2]; ++z)
    for (std::size_t y = 0; y < n[1]; ++y)
      for (std::size_t x = 0; x < n[0]; ++x, ++i) {
        const std::uint32_t l = result.labels[i];
        if (l >= result.segments.size() || result.segments[l].state != State::occupied) continue;
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(first[0] + long(x)),
                                     static_cast<octomap::key_type>(first[1] + long(y)),
                                     static_cast<octomap::key_type>(first[2] + long(z)));
        const double p = std::min(std::max(double(grid.p[i]), 1e-6), 1 - 1e-6);
        const float lo = std::max(floor_logodds, octomap::logodds(p));
        // lazy_eval: no pruning, which would merge neighbours of different colours.
        octomap::ColorOcTreeNode* node = tree->setNodeValue(key, lo, true);
        const Rgb c = segment_colour(l);
        if (node) node->setColor(c.r, c.g, c.b);
      }
  tree->updateInnerOccupancy();
  if (placement) *placement = place;
  return tree;
}

OctreePlacement write_segments_octree(const std::string& path, const Grid& grid, const Result& result,
                                      StagedFiles* into) {
  OctreePlacement place;
  const std::unique_ptr<octomap::ColorOcTree> tree = segments_octree(grid, result, &place);
  write_file_atomically(
      path,
      [&](std::ostream& os) {
        if (!tree->write(os)) throw Error(Status::io, "OctoMap could not write '" + path + "'");
      },
      into);
  return place;
}

}  // namespace occseg
