// Rule 6 (rules/objects.hpp, proximity) on random state maps against its definition, searched
// the plain way: from each occupied segment through the unknown voxels, a path of at most
// object_gap of them to another occupied segment's voxel joins the two (transitively). The maps
// mix the cases the fast search treats apart: seeds found from the unknown or from the occupied
// side (whichever has fewer voxels), unknown segments beside one segment only, unknown segments of
// at most object_gap voxels, and large ones searched breadth-first.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <limits>
#include <map>
#include <set>
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

namespace {

// Rules 6-8 as docs/algorithm.md states them, the plain way (a search per occupied segment, every
// voxel's faces and window read): the groups, as a root per segment, and each root's state.
struct PlainGroups {
  std::vector<std::uint32_t> root;
  std::vector<std::uint8_t> state;
};

PlainGroups plain_rules(const Dims& d, const std::vector<std::uint8_t>& states, const LabelArray& labels,
                        const std::vector<Segment>& segments, int gap, std::uint64_t min_object, std::uint64_t min_pocket) {
  const std::size_t S = segments.size(), n = d.count();
  std::vector<std::uint32_t> parent(S);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t i) {
    while (parent[i] != i) i = parent[i];
    return i;
  };
  const auto unite = [&](std::uint32_t a, std::uint32_t b) {  // the smaller id is the root
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  std::vector<std::uint8_t> st(S);
  for (std::size_t s = 0; s < S; ++s) st[s] = static_cast<std::uint8_t>(segments[s].state);
  const auto faces = [&](std::size_t i, auto&& fn) {
    const std::size_t x = i % d.nx, y = (i / d.nx) % d.ny, z = i / (d.nx * d.ny);
    if (x > 0) fn(i - 1);
    if (x + 1 < d.nx) fn(i + 1);
    if (y > 0) fn(i - d.nx);
    if (y + 1 < d.ny) fn(i + d.nx);
    if (z > 0) fn(i - d.nx * d.ny);
    if (z + 1 < d.nz) fn(i + d.nx * d.ny);
  };
  const auto sizes = [&] {
    std::vector<std::uint64_t> size(S, 0);
    for (std::size_t s = 0; s < S; ++s) size[find(static_cast<std::uint32_t>(s))] += segments[s].voxels;
    return size;
  };
  if (gap > 0) {
    const std::vector<std::uint32_t> g = reference_groups(d, states, labels, S, gap);
    for (std::uint32_t s = 0; s < S; ++s) unite(s, g[s]);
  }
  if (min_object > 0) {  // rule 7: decided for all small groups, then made
    const std::vector<std::uint64_t> size = sizes();
    const long r = gap + 1;
    std::vector<std::pair<long, std::uint32_t>> best(S, {std::numeric_limits<long>::max(), 0});
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t s = labels[i];
      if (st[s] != O || size[find(s)] >= min_object) continue;
      auto& b = best[find(s)];
      const long x = long(i % d.nx), y = long((i / d.nx) % d.ny), z = long(i / (d.nx * d.ny));
      for (long zz = z - r; zz <= z + r; ++zz)
        for (long yy = y - r; yy <= y + r; ++yy)
          for (long xx = x - r; xx <= x + r; ++xx) {
            if (xx < 0 || yy < 0 || zz < 0 || xx >= long(d.nx) || yy >= long(d.ny) || zz >= long(d.nz)) continue;
            const std::uint32_t l = labels[std::size_t(xx) + d.nx * (std::size_t(yy) + d.ny * std::size_t(zz))];
            if (st[l] != O || size[find(l)] < min_object) continue;
            const long dd = (xx - x) * (xx - x) + (yy - y) * (yy - y) + (zz - z) * (zz - z);
            if (dd < b.first || (dd == b.first && find(l) < b.second)) b = {dd, find(l)};
          }
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    for (std::uint32_t s = 0; s < S; ++s)
      if (find(s) == s && best[s].first != std::numeric_limits<long>::max()) joins.push_back({s, best[s].second});
    for (const auto& j : joins) unite(j.first, j.second);
  }
  if (min_pocket > 0) {  // rule 8
    std::size_t main = S;
    for (std::size_t s = 0; s < S; ++s)
      if (st[s] == F && (main == S || segments[s].voxels > segments[main].voxels)) main = s;
    std::vector<char> pocket(S, 0);
    for (std::size_t s = 0; s < S; ++s)
      if (st[s] == F && s != main && segments[s].voxels < min_pocket) pocket[s] = 1, st[s] = U;
    for (std::size_t i = 0; i < n; ++i)
      if (pocket[labels[i]])
        faces(i, [&](std::size_t j) {
          if (labels[j] != labels[i] && st[labels[j]] == U) unite(labels[i], labels[j]);
        });
    const std::vector<std::uint64_t> size = sizes();
    std::map<std::uint32_t, std::map<std::uint32_t, std::uint64_t>> shared;  // small group -> occupied group -> faces
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t g = find(labels[i]);
      if (st[labels[i]] != U || size[g] >= min_pocket) continue;
      faces(i, [&](std::size_t j) {
        if (st[labels[j]] == O) ++shared[g][find(labels[j])];
      });
    }
    // The object of the most faces (a speckle, an occupied group left below min_object, only
    // when the group touches nothing else); the speckles it touches join too, each once.
    const auto speckle = [&](std::uint32_t o) { return min_object > 0 && size[o] < min_object; };
    std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    std::set<std::uint32_t> taken;
    for (const auto& [g, counts] : shared) {
      std::uint32_t to = 0;
      std::uint64_t most = 0;
      for (const auto& [o, c] : counts)  // in increasing id: ties keep the smaller
        if (!speckle(o) && c > most) most = c, to = o;
      if (most == 0)
        for (const auto& [o, c] : counts)
          if (c > most) most = c, to = o;
      joins.push_back({g, to});
      for (const auto& [o, c] : counts)
        if (o != to && speckle(o) && taken.insert(o).second) joins.push_back({o, to});
    }
    for (const auto& j : joins) unite(j.first, j.second);
  }
  PlainGroups out{std::vector<std::uint32_t>(S), std::vector<std::uint8_t>(S, 0)};
  for (std::uint32_t s = 0; s < S; ++s) out.root[s] = find(s);
  for (std::uint32_t s = 0; s < S; ++s)
    if (out.root[s] == s) out.state[s] = st[s];
  for (std::uint32_t s = 0; s < S; ++s)
    if (st[s] == O) out.state[out.root[s]] = O;
  return out;
}

}  // namespace

TEST(ObjectsProximity, AllThreeRulesMatchThePlainOnesOnRandomMaps) {
  const Dims d{21, 16, 12};
  const int mixes[][2] = {{300, 150}, {250, 650}, {200, 400}, {450, 450}, {600, 250}};
  std::uint64_t h = 0xD1B54A32D192ED03ull;
  int maps = 0, pockets = 0, speckles = 0;
  for (const auto& mix : mixes)
    for (int gap : {0, 1, 2, 4})
      for (const int min : {3, 9}) {
        std::vector<std::uint8_t> states(d.count());
        for (auto& s : states) {
          const int r = static_cast<int>(next(h) % 1000);
          s = r < mix[0] ? F : (r < mix[0] + mix[1] ? U : O);
        }
        Grid grid(d, 0.5f);
        for (std::size_t i = 0; i < states.size(); ++i) grid.p[i] = states[i] == O ? 0.9f : (states[i] == U ? 0.5f : 0.1f);
        LabelArray labels;
        std::vector<Segment> segments;
        label_components(states, grid, labels, segments, 1, false);
        const PlainGroups want = plain_rules(d, states, labels, segments, gap, min, min);
        for (int threads : {1, 3}) {
          LabelArray grouped = labels;
          std::vector<Segment> table = segments;
          Params p;
          p.object_gap = gap;
          p.min_object_voxels = min;
          p.min_pocket_voxels = min;
          p.threads = threads;
          group_objects(grid, grouped, table, p);
          std::map<std::uint32_t, std::uint32_t> to_new, to_ref;
          bool same = true;
          for (std::size_t i = 0; i < labels.size() && same; ++i) {
            const std::uint32_t r = want.root[labels[i]], g = grouped[i];
            same = to_new.emplace(r, g).first->second == g && to_ref.emplace(g, r).first->second == r &&
                   static_cast<std::uint8_t>(table[g].state) == want.state[r];
          }
          EXPECT_TRUE(same) << "mix " << mix[0] << "/" << mix[1] << ", gap " << gap << ", min " << min << ", "
                            << threads << " threads";
        }
        ++maps;
        for (std::size_t s = 0; s < segments.size(); ++s) {
          pockets += segments[s].state == State::free && want.state[want.root[s]] != static_cast<std::uint8_t>(F);
          speckles += segments[s].state == State::occupied && segments[s].voxels < std::uint64_t(min) && want.root[s] != s;
        }
      }
  EXPECT_EQ(maps, 40);
  EXPECT_GT(pockets, 0);   // rule 8 turned free pockets unknown or occupied
  EXPECT_GT(speckles, 0);  // rule 7 or 6 joined small occupied segments
}
