// Stage 3 (section 3.1): the hierarchical division. Tiles of Smax, each split into its eight
// octants when the G-statistics of their histograms' 28 pairs give Gmax / Gmin > X, recursively
// down to Smin; the leaves in a fixed order.
#include "stages/divide.hpp"

#include <algorithm>
#include <atomic>
#include <tuple>

#include "occseg/parallel.hpp"
#include "occseg/registry.hpp"
#include "stages/codes.hpp"
#include "stages/histogram.hpp"
#include "util/thread_scratch.hpp"

namespace occseg {

bool should_split(const std::vector<const std::uint32_t*>& h, std::size_t bins, double x) {
  return split_by_ratio(h.size(), x, [&](std::size_t a, std::size_t b) { return g_statistic(h[a], h[b], bins); });
}

namespace {

// The histogram of block b's codes into h (`bins` counts); returns the voxels counted.
// faces_only: the codes are the built-in operator's, whose kNoTexture voxels lie only on the
// map's outer faces, so a block inside is counted without testing each voxel, and its flat code
// (LBP 63: no neighbour below the centre, contrast level 0) is most voxels, its local maxima
// (LBP 0, level 0) the next most. Other codes: the block's first voxel's code is the guess.
std::uint64_t count_block(const kernels::DivideKernels& k, const detail::code_t* codes, const Dims& dims,
                          const Block& b, std::size_t bins, std::uint32_t* h, bool faces_only) {
  const bool inside = faces_only && b.lo[0] > 0 && b.lo[1] > 0 && b.lo[2] > 0 && b.hi[0] < dims.nx &&
                      b.hi[1] < dims.ny && b.hi[2] < dims.nz;
  kernels::BlockCodes in{codes, dims, b, !inside, 0, 0};
  if (faces_only) {
    in.common = static_cast<kernels::code_t>(bins / 64 * 63);
    in.second = 0;
  } else {
    in.common = in.second = codes[b.lo[0] + dims.nx * (b.lo[1] + dims.ny * std::size_t(b.lo[2]))];
  }
  k.count(in, bins, h);
  return inside ? b.volume() : k.total(h, bins);
}

}  // namespace

void count_codes(const TextureMap& texture, const Dims& dims, const Block& b, std::size_t bins, std::uint32_t* h,
                 const kernels::Table& k) {
  count_block(k.divide, reinterpret_cast<const detail::code_t*>(texture.codes.data()), dims, b, bins, h, false);
}

namespace {

// One octant's histogram with what its pairs need of it: its total first (it decides whether the
// octant takes part) and its own sums of eq. (1) once a pair needs them (`complete`): a block
// that splits after its first pairs never needs most of its octants' sums.
struct Child {
  std::uint32_t* h = nullptr;  // `stride` counts, zero beyond `bins`
  HistogramSums sums;
  bool complete = false;
};

// The rules of section 3.1 and the kernels they run on, shared by the threads of one division.
struct Divider {
  const Grid& grid;
  const detail::code_t* codes;
  const Params& params;
  const kernels::DivideKernels& k;
  const XLogX& xl;
  std::size_t bins;
  std::size_t stride;     // counts per histogram: bins padded with zeros to whole vectors (64)
  const Similarity* sim;  // params.similarity, or nullptr for the G-statistic computed here
  bool faces_only;        // the built-in operator's codes (count_block)

  std::uint64_t count(const Block& b, std::uint32_t* h) const {
    return count_block(k, codes, grid.dims, b, bins, h, faces_only);
  }

  // Per-thread room for the values one sum lists.
  std::uint32_t* value_list() const {
    thread_local detail::ThreadScratch<std::uint32_t> storage;
    if (storage.size() < stride + 16) storage.resize(stride + 16);
    return storage.data();
  }

  Child& complete(Child& c) const {
    if (!c.complete) {
      std::uint32_t* const v = value_list();
      const std::size_t m = k.nonzero_values(c.h, nullptr, stride, v);
      std::uint64_t n = 0;
      for (std::size_t i = 0; i < m; ++i) n += v[i];
      c.sums = {n, lane_sum(xl, v, m)};
      c.complete = true;
    }
    return c;
  }

  // Eq. (1) for a pair of octants, g_statistic(a.h, b.h, bins) bit for bit: the same terms in the
  // same order (the bins where both are empty have no term).
  double g(Child& a, Child& b) const {
    const HistogramSums &sa = complete(a).sums, &sb = complete(b).sums;
    std::uint32_t* const v = value_list();
    return g_from_sums(xl, sa, sb, lane_sum(xl, v, k.nonzero_values(a.h, b.h, stride, v)));
  }

  // Eq. (2) over the n octants that take part.
  bool split(Child* const* used, std::size_t n) const {
    if (sim)  // every pair: the host checks each value a plugin returns
      return split_by_ratio(
          n, params.split_ratio,
          [&](std::size_t a, std::size_t b) { return compare_histograms(*sim, used[a]->h, used[b]->h, bins); },
          /*every_pair=*/true);
    return split_by_ratio(n, params.split_ratio, [&](std::size_t a, std::size_t b) { return g(*used[a], *used[b]); });
  }

  // The octants of block b of nominal edge `size` (its low corner a multiple of `size`), clipped
  // by b's far faces; empty ones left out. Returns how many.
  static int octants(const Block& b, std::uint32_t size, Block* out) {
    const std::uint32_t half = size / 2;
    int n = 0;
    for (int o = 0; o < 8; ++o) {
      Block c;
      bool empty = false;
      for (int a = 0; a < 3; ++a) {
        const std::uint32_t mid = b.lo[a] + half;
        const bool upper = (o >> a) & 1;
        c.lo[a] = upper ? mid : b.lo[a];
        c.hi[a] = upper ? b.hi[a] : std::min(mid, b.hi[a]);
        if (c.lo[a] >= c.hi[a]) empty = true;
      }
      if (!empty) out[n++] = c;
    }
    return n;
  }

  // Section 3.1 on one block of a top block's octree t (Octree or CountOnDemand below): a block
  // of Smin is a leaf; a larger one is split into its octants when eq. (2) says so over their
  // histograms, and each octant divided in turn, depth first (the leaves' fixed order).
  template <class Tree>
  void descend(Tree& t, const typename Tree::Node& node, std::vector<Block>& leaves) const {
    if (t.size(node) <= static_cast<std::uint32_t>(params.smin)) {
      leaves.push_back(t.block(node));
      return;
    }
    typename Tree::Node kids[8];
    const int nk = t.octants(node, kids);
    if (nk == 1) {  // the map's edge left a single octant: nothing to compare, it replaces its parent
      descend(t, kids[0], leaves);
      return;
    }
    Child* used[8] = {};  // the first nu are set (GCC cannot tell and warns)
    std::size_t nu = 0;
    for (int i = 0; i < nk; ++i) {
      Child& c = t.histogram(kids[i], i);
      if (c.sums.n) used[nu++] = &c;  // octants of outer-face voxels only have no texture
    }
    if (!split(used, nu)) {
      leaves.push_back(t.block(node));
      return;
    }
    for (int i = 0; i < nk; ++i) descend(t, kids[i], leaves);
  }

  // An octree whose histograms are all computed up front: codes counted once, in the Smin blocks,
  // and each larger block's histogram summed from its octants' (CountOnDemand counts a voxel again
  // at every level that examines it). Worth it when the tree's histograms fit in a few MB and a
  // Smin block holds at least a quarter as many voxels as there are bins (otherwise summing would
  // cost more than counting).
  bool use_tree() const {
    const std::uint64_t ratio = static_cast<std::uint64_t>(params.smax / params.smin);
    const std::uint64_t smin3 = static_cast<std::uint64_t>(params.smin) * params.smin * params.smin;
    return !sim && ratio * ratio * ratio * stride <= (std::uint64_t(1) << 20) && stride <= 4 * smin3;
  }
};

// The octree of one top block with a histogram per node (per thread, reused for each top block).
class Octree {
 public:
  using Node = std::uint32_t;  // index into nodes_; 0 is the top block

  explicit Octree(const Divider& d) : d_(d) {}

  Node root(const Block& top, std::uint32_t size) {
    build(top, size);
    return 0;
  }
  std::uint32_t size(Node i) const { return nodes_[i].size; }
  const Block& block(Node i) const { return nodes_[i].b; }
  int octants(Node i, Node* out) const {
    for (int k = 0; k < nodes_[i].nk; ++k) out[k] = nodes_[i].first + static_cast<Node>(k);
    return nodes_[i].nk;
  }
  Child& histogram(Node i, int) { return child_[i]; }

 private:
  struct Entry {
    Block b;
    std::uint32_t size;   // nominal edge
    std::uint32_t first;  // index of the first octant (octants are contiguous)
    std::uint8_t nk;      // number of octants, 0 for blocks of Smin
  };

  void build(const Block& top, std::uint32_t size) {
    const std::size_t stride = d_.stride;
    nodes_.clear();
    nodes_.push_back({top, size, 0, 0});
    for (std::size_t i = 0; i < nodes_.size(); ++i) {  // breadth first: octants are contiguous
      const Entry nd = nodes_[i];
      if (nd.size <= static_cast<std::uint32_t>(d_.params.smin)) continue;
      Block kids[8];
      const int nk = Divider::octants(nd.b, nd.size, kids);
      nodes_[i].first = static_cast<std::uint32_t>(nodes_.size());
      nodes_[i].nk = static_cast<std::uint8_t>(nk);
      for (int k = 0; k < nk; ++k) nodes_.push_back({kids[k], nd.size / 2, 0, 0});
    }
    const std::size_t nn = nodes_.size();
    if (hist_.size() < nn * stride) hist_.resize(nn * stride);
    child_.assign(nn, Child());
    for (std::size_t i = 0; i < nn; ++i) child_[i].h = hist_.data() + i * stride;
    // The Smin blocks first, in scan order of their corners: x-neighbours then share the cache
    // lines of their rows, where the tree's order jumps between octants and planes.
    order_.clear();
    for (std::size_t i = 1; i < nn; ++i)
      if (nodes_[i].nk == 0) order_.push_back(static_cast<std::uint32_t>(i));
    std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
      const Block &p = nodes_[a].b, &q = nodes_[b].b;
      return std::tie(p.lo[2], p.lo[1], p.lo[0]) < std::tie(q.lo[2], q.lo[1], q.lo[0]);
    });
    // While counting a block, one of the eight planes of the block eight places on (the next row
    // of blocks across the top block, when it is eight blocks wide) is prefetched, across the top
    // block's width: over eight blocks, the next row of blocks arrives whole. The hardware
    // prefetchers do not follow the jumps from row to row and plane to plane.
    const std::size_t nx = d_.grid.dims.nx, ny = d_.grid.dims.ny;
    const std::size_t row_bytes = (top.hi[0] - top.lo[0]) * sizeof(detail::code_t);
    for (std::size_t j = 0; j < order_.size(); ++j) {
      if (j + 8 < order_.size()) {
        const Block& ahead = nodes_[order_[j + 8]].b;
        const std::size_t z = ahead.lo[2] + j % 8;
        if (z < ahead.hi[2])
          for (std::size_t y = ahead.lo[1]; y < ahead.hi[1]; ++y) {
            const char* r = reinterpret_cast<const char*>(d_.codes + nx * (y + ny * z) + top.lo[0]);
            for (std::size_t q = 0; q < row_bytes; q += 64) __builtin_prefetch(r + q);
            __builtin_prefetch(r + row_bytes - 1);
          }
      }
      Child& c = child_[order_[j]];
      c.sums.n = d_.count(nodes_[order_[j]].b, c.h);
    }
    for (std::size_t i = nn; i-- > 1;) {  // octants after their parent: bottom up
      const Entry& nd = nodes_[i];
      if (nd.nk == 0) continue;
      std::uint32_t* h = child_[i].h;
      const std::uint32_t* first = child_[nd.first].h;
      if (nd.nk == 8) {
        d_.k.sum_eight(h, first, stride, d_.bins);
      } else {
        std::copy(first, first + d_.bins, h);
        for (int k = 1; k < nd.nk; ++k) d_.k.add_counts(h, first + k * stride, d_.bins);
      }
      // Voxels counted, summed up the tree (the integers any summing of the histogram gives).
      for (int k = 0; k < nd.nk; ++k) child_[i].sums.n += child_[nd.first + static_cast<std::size_t>(k)].sums.n;
    }
  }

  const Divider& d_;
  std::vector<Entry> nodes_;
  std::vector<std::uint32_t> hist_;  // `stride` counts per node
  std::vector<Child> child_;
  std::vector<std::uint32_t> order_;  // Smin nodes in the order they are counted
};

// The octree of one top block walked top-down, each examined block's octants counted when it is
// examined (eight histograms per thread, reused: a block's octants are no longer needed once its
// split is decided).
class CountOnDemand {
 public:
  struct Node {
    Block b;
    std::uint32_t size;  // nominal edge
  };

  explicit CountOnDemand(const Divider& d) : d_(d), hist_(8 * d.stride, 0) {}

  Node root(const Block& top, std::uint32_t size) const { return {top, size}; }
  std::uint32_t size(const Node& n) const { return n.size; }
  const Block& block(const Node& n) const { return n.b; }
  int octants(const Node& n, Node* out) const {
    Block kids[8];
    const int nk = Divider::octants(n.b, n.size, kids);
    for (int k = 0; k < nk; ++k) out[k] = {kids[k], n.size / 2};
    return nk;
  }
  // The histogram of octant n, the k-th of its parent.
  Child& histogram(const Node& n, int k) {
    Child& c = kids_[k];
    c.h = hist_.data() + static_cast<std::size_t>(k) * d_.stride;
    c.sums = {d_.count(n.b, c.h), 0};
    c.complete = false;
    return c;
  }

 private:
  const Divider& d_;
  std::vector<std::uint32_t> hist_;
  Child kids_[8];
};

}  // namespace

std::vector<Block> divide(const Grid& grid, const TextureMap& tex, const Params& params, const kernels::Table& k) {
  return detail::divide_codes(grid, reinterpret_cast<const detail::code_t*>(tex.codes.data()), tex.code_count(), params,
                              false, k);
}

std::vector<Block> detail::divide_codes(const Grid& grid, const code_t* codes, int code_count, const Params& params,
                                        bool faces_only, const kernels::Table& k) {
  // Tiles of Smax anchored at voxel (0, 0, 0), clipped by the map's far faces.
  const std::uint32_t s = static_cast<std::uint32_t>(params.smax);
  const std::size_t n[3] = {grid.dims.nx, grid.dims.ny, grid.dims.nz};
  std::size_t t[3];
  for (int a = 0; a < 3; ++a) t[a] = (n[a] + s - 1) / s;
  const std::size_t tops = t[0] * t[1] * t[2];
  const auto top_block = [&](std::size_t i) {
    const std::size_t c[3] = {i % t[0], (i / t[0]) % t[1], i / (t[0] * t[1])};
    Block b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = static_cast<std::uint32_t>(c[a] * s);
      b.hi[a] = static_cast<std::uint32_t>(std::min<std::size_t>(n[a], (c[a] + 1) * s));
    }
    return b;
  };
  const std::size_t bins = static_cast<std::size_t>(code_count);
  const Divider d{grid, codes, params, k.divide, xlogx_table(), bins, (bins + 63) / 64 * 64,
                  division_similarity(params), faces_only};
  const bool tree = d.use_tree();
  // Threads take top blocks one at a time from a shared counter: they differ a lot in cost
  // (uniform ones never split), and fixed shares leave threads idle. Each top block's leaves go to
  // its own list, so the result does not depend on who took it.
  std::vector<std::vector<Block>> per_top(tops);
  const std::size_t workers = std::min<std::size_t>(tops, static_cast<std::size_t>(resolve_threads(params.threads)));
  std::atomic<std::size_t> next{0};
  parallel_for(workers, params.threads, [&](std::size_t, std::size_t) {
    const auto take_tops = [&](auto& octree) {
      for (std::size_t i; (i = next.fetch_add(1, std::memory_order_relaxed)) < tops;)
        d.descend(octree, octree.root(top_block(i), s), per_top[i]);
    };
    if (tree) {
      Octree o(d);
      take_tops(o);
    } else {
      CountOnDemand o(d);
      take_tops(o);
    }
  });
  std::vector<Block> leaves;
  for (auto& v : per_top) leaves.insert(leaves.end(), v.begin(), v.end());
  return leaves;
}

}  // namespace occseg
