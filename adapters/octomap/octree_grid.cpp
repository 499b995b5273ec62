// OctoMap trees to dense grids: leaves are painted block by block into the dense voxels they
// overlap, so pruned (large) leaves cost one box each, not one voxel each.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/octomap_tree.hpp"

namespace occseg {

void OctreeOptions::validate() const {
  if (!(voxel_size >= 0) || !std::isfinite(voxel_size))
    throw Error(Status::invalid_argument, "voxel size " + std::to_string(voxel_size) + " is not >= 0");
  if (bbox)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(bbox->min[k]) || !std::isfinite(bbox->max[k]) || !(bbox->max[k] > bbox->min[k]))
        throw Error(Status::invalid_argument, "bounding box axis " + std::string(1, "xyz"[k]) + " is empty or not finite");
}

namespace {

template <typename Tree>
Grid tree_to_grid(const Tree& tree, const OctreeOptions& o) {
  o.validate();
  const double res = tree.getResolution();
  const int depth = static_cast<int>(tree.getTreeDepth());
  const long centre = long(1) << (depth - 1);  // octomap's tree_max_val: key of coordinate 0
  long f = 1;
  if (o.voxel_size > 0) {
    // The ratio is bounded before it becomes an integer (a voxel larger than the whole key
    // range, 2^16 tree voxels, is no multiple this tree can use).
    const double ratio = o.voxel_size / res;
    if (!(ratio >= 0.5 && ratio <= 65536))
      throw Error(Status::invalid_argument, "voxel size " + std::to_string(o.voxel_size) +
                                                " m is not a whole multiple of the tree's resolution " +
                                                std::to_string(res) + " m between 1 and 65536");
    f = std::lround(ratio);
    if (f < 1 || std::fabs(double(f) * res - o.voxel_size) > 1e-6 * o.voxel_size)
      throw Error(Status::invalid_argument, "voxel size " + std::to_string(o.voxel_size) +
                                                " m is not a whole multiple of the tree's resolution " +
                                                std::to_string(res) + " m");
  }
  // The box in tree keys, [lo, hi) per axis.
  long lo[3], hi[3];
  if (o.bbox) {
    for (int k = 0; k < 3; ++k) {
      // In tree voxels, still as doubles: a box of 1e300 m would overflow the conversion to an
      // integer key (undefined; it gave a one-voxel map at -7e17 m). The count is bounded as
      // frame_for_box bounds it for point clouds, and a corner beyond 2^50 tree voxels from the
      // origin is refused too, so every key below is exact in a long.
      const double a = std::floor(o.bbox->min[k] / res + 1e-9), b = std::ceil(o.bbox->max[k] / res - 1e-9);
      if (!(b - a <= double(kMaxVoxels) * double(f)))
        throw Error(Status::bad_dims, "bounding box needs too many voxels of " + std::to_string(res * double(f)) + " m");
      constexpr double kFar = 1125899906842624.0;  // 2^50
      if (!(std::fabs(a) <= kFar && std::fabs(b) <= kFar))
        throw Error(Status::bad_dims, "bounding box axis " + std::string(1, "xyz"[k]) +
                                          " lies more than 2^50 voxels of " + std::to_string(res) + " m from the origin");
      lo[k] = static_cast<long>(a) + centre;
      hi[k] = static_cast<long>(b) + centre;
      hi[k] = std::max(hi[k], lo[k] + 1);
    }
  } else {
    bool any = false;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      const octomap::OcTreeKey k0 = it.getIndexKey();
      const long side = long(1) << (depth - static_cast<int>(it.getDepth()));
      for (int k = 0; k < 3; ++k) {
        lo[k] = any ? std::min(lo[k], long(k0[k])) : long(k0[k]);
        hi[k] = any ? std::max(hi[k], long(k0[k]) + side) : long(k0[k]) + side;
      }
      any = true;
    }
    if (!any) throw Error(Status::bad_value, "the tree has no known voxel and no bounding box was given");
  }
  std::size_t n[3];
  for (int k = 0; k < 3; ++k) {
    const long cells = (hi[k] - lo[k] + f - 1) / f;
    n[k] = static_cast<std::size_t>(cells);
  }
  Dims dims{n[0], n[1], n[2]};
  check_dims(dims);
  Grid g(dims, 0.5f, res * double(f));
  for (int k = 0; k < 3; ++k) g.origin[k] = double(lo[k] - centre) * res;

  const bool mean = o.coarsen == Coarsen::mean && f > 1;
  const float none = -std::numeric_limits<float>::infinity();
  std::vector<float> max_lo(mean ? 0 : dims.count(), none);
  std::vector<double> sum(mean ? dims.count() : 0, 0.0);
  std::vector<std::uint64_t> cnt(mean ? dims.count() : 0, 0);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k0 = it.getIndexKey();
    const long side = long(1) << (depth - static_cast<int>(it.getDepth()));
    long a[3], b[3];  // the leaf clipped to the box, in keys relative to lo
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      a[k] = std::max(long(k0[k]), lo[k]) - lo[k];
      b[k] = std::min(long(k0[k]) + side, lo[k] + long(n[k]) * f) - lo[k];
      inside = inside && a[k] < b[k];
    }
    if (!inside) continue;
    const float l = it->getLogOdds();
    const double p = 1.0 / (1.0 + std::exp(-double(l)));
    for (long cz = a[2] / f; cz <= (b[2] - 1) / f; ++cz)
      for (long cy = a[1] / f; cy <= (b[1] - 1) / f; ++cy)
        for (long cx = a[0] / f; cx <= (b[0] - 1) / f; ++cx) {
          const std::size_t i = g.index(cx, cy, cz);
          if (!mean) {
            max_lo[i] = std::max(max_lo[i], l);
            continue;
          }
          // Tree voxels of this leaf inside dense voxel (cx, cy, cz).
          std::uint64_t m = 1;
          const long c[3] = {cx, cy, cz};
          for (int k = 0; k < 3; ++k) m *= std::uint64_t(std::min(b[k], (c[k] + 1) * f) - std::max(a[k], c[k] * f));
          sum[i] += p * double(m);
          cnt[i] += m;
        }
  }
  for (std::size_t i = 0; i < g.p.size(); ++i) {
    if (mean) {
      if (cnt[i]) g.p[i] = static_cast<float>(sum[i] / double(cnt[i]));
    } else if (max_lo[i] != none) {
      g.p[i] = static_cast<float>(1.0 / (1.0 + std::exp(-double(max_lo[i]))));
    }
  }
  return g;
}

}  // namespace

Grid grid_from_octree(const octomap::OcTree& tree, const OctreeOptions& o) { return tree_to_grid(tree, o); }
Grid grid_from_octree(const octomap::ColorOcTree& tree, const OctreeOptions& o) { return tree_to_grid(tree, o); }
Grid grid_from_octree(const octomap::OcTreeStamped& tree, const OctreeOptions& o) { return tree_to_grid(tree, o); }

}  // namespace occseg
