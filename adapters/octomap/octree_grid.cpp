// OctoMap trees to dense grids: leaves are painted block by block into the dense voxels they
// overlap, so pruned (large) leaves cost one box each, not one voxel each.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/io_progress.hpp"
#include "occseg/octomap_tree.hpp"
#include "octree_leaves.hpp"

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

using octree_detail::Leaf;

// Every leaf of the tree, depth first, by a plain recursion over the nodes: the same leaves as
// OctoMap's leaf iterator (which keeps a stack of node, key and depth per step), walked once.
template <typename Tree, typename Node>
void collect_leaves(const Tree& tree, const Node* node, unsigned depth, unsigned max_depth, const std::uint16_t lo[3],
                    std::vector<Leaf>& out) {
  if (!tree.nodeHasChildren(node)) {
    out.push_back({{lo[0], lo[1], lo[2]}, static_cast<std::uint8_t>(max_depth - depth), node->getLogOdds()});
    return;
  }
  const std::uint16_t half = static_cast<std::uint16_t>(1u << (max_depth - depth - 1));
  for (unsigned i = 0; i < 8; ++i) {
    if (!tree.nodeChildExists(node, i)) continue;
    const std::uint16_t child[3] = {static_cast<std::uint16_t>(lo[0] + ((i & 1) ? half : 0)),
                                    static_cast<std::uint16_t>(lo[1] + ((i & 2) ? half : 0)),
                                    static_cast<std::uint16_t>(lo[2] + ((i & 4) ? half : 0))};
    collect_leaves(tree, tree.getNodeChild(node, i), depth + 1, max_depth, child, out);
  }
}

template <typename Tree>
Grid tree_to_grid(const Tree& tree, const OctreeOptions& o) {
  o.validate();
  const double res = tree.getResolution();
  const int depth = static_cast<int>(tree.getTreeDepth());
  std::vector<Leaf> leaves;
  if (tree.getRoot()) {
    leaves.reserve(tree.size());  // at most one leaf per node
    const std::uint16_t zero[3] = {0, 0, 0};
    collect_leaves(tree, tree.getRoot(), 0, static_cast<unsigned>(depth), zero, leaves);
  }
  return octree_detail::grid_from_leaves(leaves, res, depth, o);
}

}  // namespace

namespace octree_detail {

Grid grid_from_leaves(std::vector<Leaf>& leaves, double res, int depth, const OctreeOptions& o) {
  o.validate();
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
  report_progress(o.progress, 0.5);
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
    if (leaves.empty()) throw Error(Status::bad_value, "the tree has no known voxel and no bounding box was given");
    for (int k = 0; k < 3; ++k) {
      lo[k] = long(leaves[0].key[k]);
      hi[k] = lo[k] + (long(1) << leaves[0].level);
    }
    for (const Leaf& leaf : leaves)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], long(leaf.key[k]));
        hi[k] = std::max(hi[k], long(leaf.key[k]) + (long(1) << leaf.level));
      }
  }
  std::size_t n[3];
  for (int k = 0; k < 3; ++k) {
    const long cells = (hi[k] - lo[k] + f - 1) / f;
    n[k] = static_cast<std::size_t>(cells);
  }
  Dims dims{n[0], n[1], n[2]};
  check_dims(dims);
  const bool mean = o.coarsen == Coarsen::mean && f > 1;
  // Rule max: the largest probability of the leaves a voxel overlaps is the probability of their
  // largest log-odds (the logistic function is monotonic), so probabilities are painted directly,
  // over a value no probability has (-1: unknown, 0.5 at the end).
  constexpr float kUnknown = -1.0f;
  Grid g(dims, mean ? 0.5f : kUnknown, res * double(f));
  for (int k = 0; k < 3; ++k) g.origin[k] = double(lo[k] - centre) * res;

  std::vector<double> sum(mean ? dims.count() : 0, 0.0);
  std::vector<std::uint64_t> cnt(mean ? dims.count() : 0, 0);
  // Leaves mostly share a few log-odds values (a .bt holds two: the clamping bounds), so the
  // logistic function is evaluated when the value changes only.
  float last_l = std::numeric_limits<float>::quiet_NaN();
  double p = 0.5;
  // The leaf clipped to the box, in tree keys relative to lo; false when nothing is left.
  auto clip = [&](const Leaf& leaf, long a[3], long b[3]) {
    const long side = long(1) << leaf.level;
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      a[k] = std::max(long(leaf.key[k]), lo[k]) - lo[k];
      b[k] = std::min(long(leaf.key[k]) + side, lo[k] + long(n[k]) * f) - lo[k];
      inside = inside && a[k] < b[k];
    }
    return inside;
  };
  auto probability = [&](const Leaf& leaf) {
    if (!(leaf.log_odds == last_l)) {
      last_l = leaf.log_odds;
      p = 1.0 / (1.0 + std::exp(-double(last_l)));
    }
    return static_cast<float>(p);
  };
  if (f == 1 && !mean) {  // the tree's own resolution: keys are voxel indices, no division
    for (const Leaf& leaf : leaves) {
      long a[3], b[3];
      if (!clip(leaf, a, b)) continue;
      const float pf = probability(leaf);
      for (long z = a[2]; z < b[2]; ++z)
        for (long y = a[1]; y < b[1]; ++y) {
          float* v = g.p.data() + g.index(0, std::size_t(y), std::size_t(z));
          for (long x = a[0]; x < b[0]; ++x) v[x] = std::max(v[x], pf);
        }
    }
    leaves.clear();  // painted
  }
  for (const Leaf& leaf : leaves) {
    long a[3], b[3];
    if (!clip(leaf, a, b)) continue;
    const float pf = probability(leaf);
    const long x0 = a[0] / f, x1 = (b[0] - 1) / f;
    for (long cz = a[2] / f; cz <= (b[2] - 1) / f; ++cz)
      for (long cy = a[1] / f; cy <= (b[1] - 1) / f; ++cy) {
        const std::size_t row = g.index(0, cy, cz);
        if (!mean) {
          float* v = g.p.data() + row;
          for (long cx = x0; cx <= x1; ++cx) v[cx] = std::max(v[cx], pf);
          continue;
        }
        for (long cx = x0; cx <= x1; ++cx) {
          const std::size_t i = row + std::size_t(cx);
          // Tree voxels of this leaf inside dense voxel (cx, cy, cz).
          std::uint64_t m = 1;
          const long c[3] = {cx, cy, cz};
          for (int k = 0; k < 3; ++k) m *= std::uint64_t(std::min(b[k], (c[k] + 1) * f) - std::max(a[k], c[k] * f));
          sum[i] += p * double(m);
          cnt[i] += m;
        }
      }
  }
  if (mean) {
    for (std::size_t i = 0; i < g.p.size(); ++i)
      if (cnt[i]) g.p[i] = static_cast<float>(sum[i] / double(cnt[i]));
  } else {
    for (float& v : g.p) v = v == kUnknown ? 0.5f : v;
  }
  report_progress(o.progress, 1.0);
  return g;
}

}  // namespace octree_detail

Grid grid_from_octree(const octomap::OcTree& tree, const OctreeOptions& o) { return tree_to_grid(tree, o); }
Grid grid_from_octree(const octomap::ColorOcTree& tree, const OctreeOptions& o) { return tree_to_grid(tree, o); }
Grid grid_from_octree(const octomap::OcTreeStamped& tree, const OctreeOptions& o) { return tree_to_grid(tree, o); }

}  // namespace occseg
