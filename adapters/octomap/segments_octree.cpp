// segments.ot: occupied segments as a ColorOcTree (occseg/octomap_segments.hpp).
#include <algorithm>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>
#include <cmath>
#include <string>

#include "occseg/error.hpp"
#include "occseg/octomap_tree.hpp"
#include "occseg/segment_colour.hpp"

namespace occseg {

namespace {

// Where the map's voxel (0, 0, 0) lies in the tree's keys, and the shift that put it there.
struct KeyFrame {
  long first[3];
  OctreePlacement place;
};

KeyFrame key_frame(const Grid& grid, const Result& result, unsigned depth) {
  if (!(result.dims == grid.dims) || result.labels.size() != grid.p.size())
    throw Error(Status::invalid_argument, "the result's dims do not match the map's");
  const double v = grid.voxel_size;
  const long centre = long(1) << (depth - 1);  // OctoMap's tree_max_val: key of coordinate 0
  const double keys = double(2 * centre);
  KeyFrame f;
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
      f.place.snapped = true;
      f.place.shift[k] = (m - steps) * v;
    }
    f.first[k] = static_cast<long>(m) + centre;
  }
  return f;
}

// The log-odds a voxel's leaf holds (before OctoMap's clamping).
float leaf_logodds(float p, float floor_logodds) {
  const double q = std::min(std::max(double(p), 1e-6), 1 - 1e-6);
  return std::max(floor_logodds, octomap::logodds(q));
}

// The bytes of ColorOcTree::writeData for the tree segments_octree builds, made straight from
// the grid: nodes in OctoMap's order (depth first, children 0..7, child i holding key bit
// x = i & 1, y = i & 2, z = i & 4), each its log-odds (float), colour (r, g, b) and a byte of
// the children present. Inner nodes as updateInnerOccupancy leaves them: the largest log-odds
// of their children, the integer mean colour of the children whose colour is not white.
class DirectTree {
 public:
  DirectTree(const Grid& g, const Result& r, const long first[3], unsigned depth, float lo_min, float lo_max)
      : g_(g), r_(r), depth_(depth), lo_min_(lo_min), lo_max_(lo_max) {
    for (int k = 0; k < 3; ++k) first_[k] = first[k];
    n_[0] = long(g.dims.nx), n_[1] = long(g.dims.ny), n_[2] = long(g.dims.nz);
    floor_ = octomap::logodds(0.7);
    occupied_.resize(r.segments.size());
    for (std::size_t i = 0; i < r.segments.size(); ++i) occupied_[i] = r.segments[i].state == State::occupied;
    // Which cubes of 8 x 8 x 8 keys hold an occupied voxel: the others are skipped whole.
    for (int k = 0; k < 3; ++k) {
      b0_[k] = first_[k] >> 3;
      bn_[k] = ((first_[k] + n_[k] - 1) >> 3) - b0_[k] + 1;
    }
    blocks_.assign(std::size_t(bn_[0] * bn_[1] * bn_[2]), 0);
    std::size_t i = 0;
    for (long z = 0; z < n_[2]; ++z)
      for (long y = 0; y < n_[1]; ++y) {
        const std::size_t row = std::size_t(((first_[1] + y) >> 3) - b0_[1]) * std::size_t(bn_[0]) +
                                std::size_t(((first_[2] + z) >> 3) - b0_[2]) * std::size_t(bn_[0] * bn_[1]);
        for (long x = 0; x < n_[0]; ++x, ++i)
          if (is_occupied(r.labels[i])) blocks_[row + std::size_t(((first_[0] + x) >> 3) - b0_[0])] = 1;
      }
  }
  // Appends the whole tree (nothing for a tree without an occupied voxel); the node count.
  std::size_t write(std::vector<char>& out) {
    out_ = &out;
    nodes_ = 0;
    float lo;
    Rgb c;
    node(0, 0, 0, 0, lo, c);
    return nodes_;
  }

 private:
  // The subtree of the cube of keys [k, k + 2^(depth - level)) on each axis; false when it holds
  // no occupied voxel (then nothing is written).
  bool node(unsigned level, long kx, long ky, long kz, float& lo, Rgb& colour) {
    const long side = long(1) << (depth_ - level);
    if (kx + side <= first_[0] || ky + side <= first_[1] || kz + side <= first_[2] || kx >= first_[0] + n_[0] ||
        ky >= first_[1] + n_[1] || kz >= first_[2] + n_[2])
      return false;
    if (level == depth_) {
      const std::size_t i = std::size_t(kx - first_[0]) +
                            g_.dims.nx * (std::size_t(ky - first_[1]) + g_.dims.ny * std::size_t(kz - first_[2]));
      const std::uint32_t l = r_.labels[i];
      if (!is_occupied(l)) return false;
      lo = std::min(std::max(leaf_logodds(g_.p[i], floor_), lo_min_), lo_max_);
      colour = segment_colour(l);
      put(lo, colour, 0);
      return true;
    }
    if (side == 8 && !blocks_[std::size_t((kx >> 3) - b0_[0]) +
                              std::size_t(bn_[0]) * (std::size_t((ky >> 3) - b0_[1]) + std::size_t(bn_[1]) * std::size_t((kz >> 3) - b0_[2]))])
      return false;
    if (side == 2) return last_inner(kx, ky, kz, lo, colour);
    const std::size_t at = out_->size();
    out_->resize(at + 8);  // this node's record, filled in once its children are known
    const long half = side / 2;
    unsigned children = 0;
    float max_lo = -std::numeric_limits<float>::max();
    int sum[3] = {0, 0, 0}, coloured = 0;
    for (unsigned i = 0; i < 8; ++i) {
      float clo;
      Rgb cc;
      if (!node(level + 1, kx + ((i & 1) ? half : 0), ky + ((i & 2) ? half : 0), kz + ((i & 4) ? half : 0), clo, cc))
        continue;
      children |= 1u << i;
      if (clo > max_lo) max_lo = clo;
      if (cc.r != 255 || cc.g != 255 || cc.b != 255) sum[0] += cc.r, sum[1] += cc.g, sum[2] += cc.b, ++coloured;
    }
    if (children == 0) {
      out_->resize(at);
      return false;
    }
    lo = max_lo;
    colour = coloured > 0 ? Rgb{std::uint8_t(sum[0] / coloured), std::uint8_t(sum[1] / coloured), std::uint8_t(sum[2] / coloured)}
                          : Rgb{255, 255, 255};
    fill(at, lo, colour, children);
    return true;
  }
  // A node of 2 x 2 x 2 leaves, the leaves read straight from the grid (node() for each, unrolled).
  bool last_inner(long kx, long ky, long kz, float& lo, Rgb& colour) {
    std::uint32_t label[8];
    std::size_t index[8];
    unsigned children = 0;
    for (unsigned i = 0; i < 8; ++i) {
      const long x = kx + long(i & 1) - first_[0], y = ky + long((i >> 1) & 1) - first_[1], z = kz + long(i >> 2) - first_[2];
      if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) continue;
      index[i] = std::size_t(x) + g_.dims.nx * (std::size_t(y) + g_.dims.ny * std::size_t(z));
      label[i] = r_.labels[index[i]];
      if (is_occupied(label[i])) children |= 1u << i;
    }
    if (children == 0) return false;
    const std::size_t at = out_->size();
    out_->resize(at + 8);
    float max_lo = -std::numeric_limits<float>::max();
    int sum[3] = {0, 0, 0}, coloured = 0;
    for (unsigned i = 0; i < 8; ++i) {
      if (!(children >> i & 1u)) continue;
      const float clo = std::min(std::max(leaf_logodds(g_.p[index[i]], floor_), lo_min_), lo_max_);
      const Rgb cc = segment_colour(label[i]);
      put(clo, cc, 0);
      if (clo > max_lo) max_lo = clo;
      if (cc.r != 255 || cc.g != 255 || cc.b != 255) sum[0] += cc.r, sum[1] += cc.g, sum[2] += cc.b, ++coloured;
    }
    lo = max_lo;
    colour = coloured > 0 ? Rgb{std::uint8_t(sum[0] / coloured), std::uint8_t(sum[1] / coloured), std::uint8_t(sum[2] / coloured)}
                          : Rgb{255, 255, 255};
    fill(at, lo, colour, children);
    return true;
  }

  void fill(std::size_t at, float lo, Rgb c, unsigned children) {
    char* p = out_->data() + at;
    std::memcpy(p, &lo, 4);
    p[4] = char(c.r), p[5] = char(c.g), p[6] = char(c.b), p[7] = char(children);
    ++nodes_;
  }
  void put(float lo, Rgb c, unsigned children) {
    const std::size_t at = out_->size();
    out_->resize(at + 8);
    fill(at, lo, c, children);
  }

  bool is_occupied(std::uint32_t l) const { return l < occupied_.size() && occupied_[l]; }

  const Grid& g_;
  const Result& r_;
  long b0_[3], bn_[3];
  std::vector<unsigned char> blocks_;
  unsigned depth_;
  float lo_min_, lo_max_, floor_ = 0;
  long first_[3], n_[3];
  std::vector<unsigned char> occupied_;
  std::vector<char>* out_ = nullptr;
  std::size_t nodes_ = 0;
};

}  // namespace

std::unique_ptr<octomap::ColorOcTree> segments_octree(const Grid& grid, const Result& result,
                                                      OctreePlacement* placement) {
  auto tree = std::make_unique<octomap::ColorOcTree>(grid.voxel_size);
  const KeyFrame f = key_frame(grid, result, tree->getTreeDepth());
  const long* first = f.first;
  const std::size_t n[3] = {grid.dims.nx, grid.dims.ny, grid.dims.nz};
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
        // lazy_eval: no pruning, which would merge neighbours of different colours.
        octomap::ColorOcTreeNode* node = tree->setNodeValue(key, leaf_logodds(grid.p[i], floor_logodds), true);
        const Rgb c = segment_colour(l);
        if (node) node->setColor(c.r, c.g, c.b);
      }
  if (tree->getRoot()) tree->updateInnerOccupancy();  // (liboctomap's would follow a null root)
  if (placement) *placement = f.place;
  return tree;
}

OctreePlacement write_segments_octree(const std::string& path, const Grid& grid, const Result& result,
                                      StagedFiles* into) {
  // The file ColorOcTree::write makes of segments_octree's tree (the same bytes: the adapter
  // tests compare them), written without building the tree: its nodes are in the order of the
  // map's cubes of keys, so one pass over them gives the file.
  const octomap::ColorOcTree shape(grid.voxel_size);  // OctoMap's depth, clamping and header
  const KeyFrame f = key_frame(grid, result, shape.getTreeDepth());
  std::vector<char> data;
  DirectTree tree(grid, result, f.first, shape.getTreeDepth(), shape.getClampingThresMinLog(),
                  shape.getClampingThresMaxLog());
  const std::size_t nodes = tree.write(data);
  std::ostringstream head;
  head << "# Octomap OcTree file" << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
       << "id " << shape.getTreeType() << "\nsize " << nodes << "\nres " << shape.getResolution() << "\ndata\n";
  const std::string h = head.str();
  write_file_atomically(
      path,
      [&](std::ostream& os) {
        os.write(h.data(), static_cast<std::streamsize>(h.size()));
        os.write(data.data(), static_cast<std::streamsize>(data.size()));
      },
      into);
  return f.place;
}

}  // namespace occseg
