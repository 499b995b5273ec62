// Rule 6 (rules/objects.hpp, proximity) on random state maps against its definition, searched
// the plain way: from each occupied segment through the unknown voxels, a path of at most
// object_gap of them to another occupied segment's voxel joins the two (transitively). The maps
// mix the cases the fast search treats apart: seeds found from the unknown or from the occupied
// side (whichever has fewer voxels), unknown segments beside one segment only, unknown segments of
// at most object_gap voxels, and large ones searched breadth-first.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <map>
#include <numeric>

#include "occseg/segment.hpp"
#include "rules/objects.hpp"
#include "stages/label.hpp"

using namespace occseg;

namespace {

constexpr std::uint8_t F = 0, U = 1, O = 2;

struct Roots {
  std::vector<std::uint32_t> p;
  explicit Roots(std::size_t n) : p(n) { std::iota(p.begin(), p.end(), 0u); }
  std::uint32_t find(std::uint32_t i) { return p[i] == i ? i : p[i] = find(p[i]); }
  void unite(std::uint32_t a, std::uint32_t b) { p[find(a)] = find(b); }
};

// The groups of the definition, as a root per segment of `labels`.
std::vector<std::uint32_t> reference_groups(const Dims& d, const std::vector<std::uint8_t>& states,
                                            const LabelArray& labels, std::size_t segments, int gap) {
  Roots roots(segments);
  const std::size_t n = d.count();
  std::vector<int> depth(n);
  for (std::uint32_t a = 0; a < segments; ++a) {
    std::deque<std::size_t> queue;
    std::fill(depth.begin(), depth.end(), -1);
    for (std::size_t i = 0; i < n; ++i)
      if (labels[i] == a && states[i] == O) depth[i] = 0, queue.push_back(i);
    while (!queue.empty()) {
      const std::size_t i = queue.front();
      queue.pop_front();
      const std::size_t x = i % d.nx, y = (i / d.nx) % d.ny, z = i / (d.nx * d.ny);
      const std::size_t faces[6] = {x > 0 ? i - 1 : n, x + 1 < d.nx ? i + 1 : n,
                                    y > 0 ? i - d.nx : n, y + 1 < d.ny ? i + d.nx : n,
                                    z > 0 ? i - d.nx * d.ny : n, z + 1 < d.nz ? i + d.nx * d.ny : n};
      for (const std::size_t j : faces) {
        if (j == n) continue;
        if (states[j] == O && labels[j] != a && depth[i] > 0) roots.unite(a, labels[j]);  // depth[i] <= gap
        if (states[j] == U && depth[j] < 0 && depth[i] < gap) depth[j] = depth[i] + 1, queue.push_back(j);
      }
    }
  }
  std::vector<std::uint32_t> out(segments);
  for (std::uint32_t s = 0; s < segments; ++s) out[s] = roots.find(s);
  return out;
}

std::uint64_t next(std::uint64_t& h) {
  h ^= h << 13;
  h ^= h >> 7;
  h ^= h << 17;
  return h;
}

}  // namespace

TEST(ObjectsProximity, GroupsAreThoseOfTheDefinitionOnRandomMaps) {
  const Dims d{23, 17, 13};
  // (free, unknown) per mille; the rest occupied. Sparse unknown (seeds from the unknown side),
  // sparse occupied (from the occupied side), and both about even.
  const int mixes[][2] = {{300, 150}, {250, 650}, {200, 400}, {100, 300}, {450, 450}};
  std::uint64_t h = 0x9E3779B97F4A7C15ull;
  int maps = 0, joined = 0;
  for (const auto& mix : mixes)
    for (int gap = 1; gap <= 5; ++gap)
      for (const bool occupied26 : {false, true}) {
        std::vector<std::uint8_t> states(d.count());
        for (auto& s : states) {
          const int r = static_cast<int>(next(h) % 1000);
          s = r < mix[0] ? F : (r < mix[0] + mix[1] ? U : O);
        }
        Grid grid(d, 0.5f);
        for (std::size_t i = 0; i < states.size(); ++i) grid.p[i] = states[i] == O ? 0.9f : (states[i] == U ? 0.5f : 0.1f);
        LabelArray labels;
        std::vector<Segment> segments;
        label_components(states, grid, labels, segments, 1, occupied26);
        const std::vector<std::uint32_t> want = reference_groups(d, states, labels, segments.size(), gap);
        LabelArray grouped = labels;
        std::vector<Segment> table = segments;
        Params p;
        p.object_gap = gap;
        p.min_object_voxels = 0;
        p.min_pocket_voxels = 0;
        group_objects(grid, grouped, table, p);
        // One new label per reference group and the other way round.
        std::map<std::uint32_t, std::uint32_t> to_new, to_ref;
        bool same = true;
        for (std::size_t i = 0; i < labels.size() && same; ++i) {
          const std::uint32_t r = want[labels[i]], g = grouped[i];
          same = to_new.emplace(r, g).first->second == g && to_ref.emplace(g, r).first->second == r;
        }
        EXPECT_TRUE(same) << "mix " << mix[0] << "/" << mix[1] << ", gap " << gap << ", 26: " << occupied26;
        ++maps;
        joined += table.size() < segments.size();
      }
  EXPECT_EQ(maps, 50);
  EXPECT_GT(joined, 30);  // the rule had something to do on most maps
}
