#include "occseg/components.hpp"

#include <algorithm>
#include <limits>

#include "occseg/error.hpp"

namespace occseg {

namespace {

// Union-find over voxel indices stored in the labels array itself (no extra memory). Roots are
// always the smallest index of their set, so the final numbering follows scan order.
inline std::uint32_t find(std::uint32_t* parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

inline std::uint32_t unite(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
  a = find(parent, a);
  b = find(parent, b);
  if (a == b) return a;
  if (a < b) std::swap(a, b);
  parent[a] = b;
  return b;
}

}  // namespace

void label_components(const std::vector<std::uint8_t>& st, const Grid& g,
                      std::vector<std::uint32_t>& labels, std::vector<Segment>& segments) {
  const std::size_t n = g.dims.count();
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw Error(Status::unsupported, "maps of " + std::to_string(n) +
                                         " voxels exceed the uint32 labels (at most 2^32 - 2 voxels)");
  const std::size_t nx = g.dims.nx, ny = g.dims.ny, sz = nx * ny;
  labels.resize(n);
  std::uint32_t* parent = labels.data();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t u = static_cast<std::uint32_t>(i);
    std::uint32_t root = u;
    const std::size_t x = i % nx, y = (i / nx) % ny, z = i / sz;
    parent[u] = u;
    if (x > 0 && st[i - 1] == st[i]) root = unite(parent, root, u - 1);
    if (y > 0 && st[i - nx] == st[i]) root = unite(parent, root, static_cast<std::uint32_t>(i - nx));
    if (z > 0 && st[i - sz] == st[i]) root = unite(parent, root, static_cast<std::uint32_t>(i - sz));
    (void)root;
  }
  // Second pass: roots get consecutive ids in scan order. A non-root's parent is a smaller index
  // of the same set, already rewritten to the set's id, so no find() (whose path compression
  // would walk over rewritten entries) is needed.
  segments.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t u = static_cast<std::uint32_t>(i);
    const std::uint32_t r = parent[u];
    std::uint32_t id;
    if (r == u) {
      id = static_cast<std::uint32_t>(segments.size());
      Segment s;
      s.id = id;
      s.state = static_cast<State>(st[i]);
      s.bbox_min = {std::numeric_limits<std::uint32_t>::max(), std::numeric_limits<std::uint32_t>::max(),
                    std::numeric_limits<std::uint32_t>::max()};
      segments.push_back(s);
    } else {
      id = labels[r];
    }
    labels[i] = id;
  }
  // Statistics, accumulated in scan order (deterministic sums).
  for (auto& s : segments) s.centroid = {0, 0, 0};
  for (std::size_t z = 0, i = 0; z < g.dims.nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x, ++i) {
        Segment& s = segments[labels[i]];
        ++s.voxels;
        s.mop += g.p[i];
        const std::uint32_t c[3] = {static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                    static_cast<std::uint32_t>(z)};
        for (int a = 0; a < 3; ++a) {
          s.bbox_min[a] = std::min(s.bbox_min[a], c[a]);
          s.bbox_max[a] = std::max(s.bbox_max[a], c[a]);
          s.centroid[a] += c[a];
        }
      }
  for (auto& s : segments) {
    const double v = static_cast<double>(s.voxels);
    s.mop /= v;
    for (int a = 0; a < 3; ++a) s.centroid[a] /= v;
  }
}

}  // namespace occseg
