// Objects out of segments (rules/objects.hpp): proximity across unknown gaps, speckles, pockets,
// then one renumbering; and the kinds of the scene table.
#include "rules/objects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>

#include "occseg/parallel.hpp"

namespace occseg {

namespace {

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);

// Union-find over segment ids whose roots are the smallest id of their set: a group's root is
// then its member with the first first voxel, and numbering roots in id order keeps the order of
// first voxels.
struct Groups {
  std::vector<std::uint32_t> parent;
  explicit Groups(std::size_t n) : parent(n) {
    for (std::size_t i = 0; i < n; ++i) parent[i] = static_cast<std::uint32_t>(i);
  }
  std::uint32_t find(std::uint32_t i) {
    while (parent[i] != i) {
      parent[i] = parent[parent[i]];
      i = parent[i];
    }
    return i;
  }
  bool unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    if (a < b) std::swap(a, b);
    parent[a] = b;
    return true;
  }
};

}  // namespace

std::uint64_t minimum_size(int voxels, const Dims& d) {
  if (voxels <= 0) return 0;
  if (d.nz > 1) return static_cast<std::uint64_t>(voxels);
  return std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::lround(std::pow(double(voxels), 2.0 / 3.0))));
}

namespace {

std::size_t box_volume(const Segment& s) {
  std::size_t v = 1;
  for (int k = 0; k < 3; ++k) v *= std::size_t(s.bbox_max[k] - s.bbox_min[k]) + 1;
  return v;
}

class Grouper {
 public:
  Grouper(const Grid& g, LabelArray& labels, std::vector<Segment>& segs, const Params& p,
          const std::vector<std::uint64_t>* band)
      : d_(g.dims), nx(d_.nx), ny(d_.ny), nz(d_.nz), sz(nx * ny), labels_(labels), segs_(segs), p_(p), band_(band),
        groups_(segs.size()), state_(segs.size()) {
    for (std::size_t s = 0; s < segs.size(); ++s) state_[s] = static_cast<std::uint8_t>(segs[s].state);
  }

  void run() {
    if (p_.object_gap > 0) proximity();
    if (p_.min_object_voxels > 0) speckles();
    if (p_.min_pocket_voxels > 0) pockets();
    if (changed_) renumber();
  }

 private:
  // Calls fn(i) for the voxels of the segments flagged in `want` (by id), in scan order within
  // each segment's box, segment after segment in id order; in one pass over the labels instead
  // when the boxes add up to more than half the map. Nothing is listed: on a noisy map the
  // occupied voxels are a third of the map.
  template <typename Fn>
  void for_members(const std::vector<char>& want, Fn&& fn) const {
    std::size_t boxes = 0;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (want[s]) boxes += box_volume(segs_[s]);
    if (2 * boxes > labels_.size()) {
      for (std::size_t i = 0; i < labels_.size(); ++i)
        if (want[labels_[i]]) fn(i);
      return;
    }
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      if (!want[s]) continue;
      const Segment& seg = segs_[s];
      for (std::size_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
        for (std::size_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
          const std::size_t row = nx * (y + ny * z);
          for (std::size_t x = seg.bbox_min[0]; x <= seg.bbox_max[0]; ++x)
            if (labels_[row + x] == s) fn(row + x);
        }
    }
  }

  void box_members(std::uint32_t s, std::vector<std::uint32_t>& out) const {
    const Segment& seg = segs_[s];
    for (std::size_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
      for (std::size_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
        const std::size_t row = nx * (y + ny * z);
        for (std::size_t x = seg.bbox_min[0]; x <= seg.bbox_max[0]; ++x)
          if (labels_[row + x] == s) out.push_back(static_cast<std::uint32_t>(row + x));
      }
  }

  // Calls fn(j) for each 6-neighbour j of voxel i inside the map.
  template <typename Fn>
  void for_faces(std::size_t i, Fn&& fn) const {
    const std::size_t x = i % nx, y = (i / nx) % ny, z = i / sz;
    if (x > 0) fn(i - 1);
    if (x + 1 < nx) fn(i + 1);
    if (y > 0) fn(i - nx);
    if (y + 1 < ny) fn(i + nx);
    if (z > 0) fn(i - sz);
    if (z + 1 < nz) fn(i + sz);
  }

  void unite(std::uint32_t a, std::uint32_t b) { changed_ |= groups_.unite(a, b); }

  // Rule 6. A breadth-first search from every occupied segment into the unknown voxels, to depth
  // object_gap - 1, keeps for each voxel reached its distance d (the unknown voxels on a shortest
  // path from an occupied one, itself included) and one segment at that distance. Two segments
  // are joined where the waves of two meet: at an unknown voxel next to an occupied voxel of
  // another segment (d = 1), or at two neighbouring voxels with d(u) + d(v) <= object_gap. Every
  // join stands for a path of at most object_gap unknown voxels; and along any such path between
  // segments A and B the segments the search kept change only at such meetings, so A and B end
  // up in one group: the groups are exactly the closure of "a path of at most object_gap unknown
  // voxels", whichever segment a tie kept. The labels of reached voxels hold the kept segment
  // during the search and get theirs back after it.
  void proximity() {
    std::vector<char> want(segs_.size(), 0);
    std::size_t occupied = 0;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (state_[s] == kOccupied) want[s] = 1, ++occupied;
    if (occupied < 2) return;
    const int gap = p_.object_gap;
    // d per voxel, 0: not reached. Zeroed pages come from the system as the search touches them.
    std::unique_ptr<std::uint8_t, void (*)(void*)> dist(static_cast<std::uint8_t*>(std::calloc(labels_.size(), 1)),
                                                        std::free);
    if (!dist) throw std::bad_alloc();
    std::uint8_t* const d = dist.get();
    std::vector<std::pair<std::uint32_t, std::uint32_t>> saved;  // (voxel, its own label)
    std::vector<std::uint32_t> layer, next;
    const auto reach = [&](std::size_t j, std::uint8_t depth, std::uint32_t from) {
      d[j] = depth;
      saved.push_back({static_cast<std::uint32_t>(j), labels_[j]});
      labels_[j] = from;
      next.push_back(static_cast<std::uint32_t>(j));
    };
    // (Reached voxels hold an occupied segment's id meanwhile, so the scan over the labels below
    // must not take them for occupied voxels: d says which they are.)
    for_members(want, [&](std::size_t i) {
      if (d[i]) return;
      const std::uint32_t a = labels_[i];
      for_faces(i, [&](std::size_t j) {
        if (d[j]) {
          if (labels_[j] != a) unite(a, labels_[j]);
        } else if (state_[labels_[j]] == kUnknown) {
          reach(j, 1, a);
        }
      });
    });
    for (int depth = 1; depth < gap; ++depth) {
      layer.swap(next);
      next.clear();
      for (const std::uint32_t u : layer) {
        const std::uint32_t a = labels_[u];
        for_faces(u, [&](std::size_t j) {
          if (d[j]) {
            if (labels_[j] != a && depth + d[j] <= gap) unite(a, labels_[j]);
          } else if (depth + 1 < gap && state_[labels_[j]] == kUnknown) {
            reach(j, static_cast<std::uint8_t>(depth + 1), a);
          }
        });
      }
    }
    for (const auto& sv : saved) labels_[sv.first] = sv.second;
  }

  // Voxels per group (at the roots); `evidence`: leaving out those the surface band added.
  std::vector<std::uint64_t> group_sizes(bool evidence = false) {
    std::vector<std::uint64_t> size(segs_.size(), 0);
    for (std::size_t s = 0; s < segs_.size(); ++s)
      size[groups_.find(static_cast<std::uint32_t>(s))] += segs_[s].voxels - (evidence && band_ ? (*band_)[s] : 0);
    return size;
  }

  // Rule 7. The joins are decided for all small groups first and made afterwards, so a small
  // group never joins through another small one and the order of the groups changes nothing.
  void speckles() {
    const std::uint64_t min = minimum_size(p_.min_object_voxels, d_);
    const std::vector<std::uint64_t> size = group_sizes(/*evidence=*/true);
    std::vector<char> want(segs_.size(), 0);
    bool any = false;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (state_[s] == kOccupied && size[groups_.find(static_cast<std::uint32_t>(s))] < min) want[s] = 1, any = true;
    if (!any) return;
    const long r = p_.object_gap + 1;
    struct Best {
      long dist = std::numeric_limits<long>::max();
      std::uint32_t to = 0;
    };
    std::vector<Best> best(segs_.size());  // at the small groups' roots
    std::vector<std::uint32_t> vox;
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      if (!want[s]) continue;
      vox.clear();
      box_members(static_cast<std::uint32_t>(s), vox);
      Best& b = best[groups_.find(static_cast<std::uint32_t>(s))];
      for (const std::uint32_t i : vox) {
        const long x = static_cast<long>(i % nx), y = static_cast<long>((i / nx) % ny), z = static_cast<long>(i / sz);
        for (long zz = std::max(0L, z - r); zz <= std::min<long>(nz - 1, z + r); ++zz)
          for (long yy = std::max(0L, y - r); yy <= std::min<long>(ny - 1, y + r); ++yy)
            for (long xx = std::max(0L, x - r); xx <= std::min<long>(nx - 1, x + r); ++xx) {
              const std::uint32_t l = labels_[static_cast<std::size_t>(xx) + nx * (yy + ny * zz)];
              if (state_[l] != kOccupied) continue;
              const std::uint32_t g = groups_.find(l);
              if (size[g] < min) continue;
              const long dd = (xx - x) * (xx - x) + (yy - y) * (yy - y) + (zz - z) * (zz - z);
              if (dd < b.dist || (dd == b.dist && g < b.to)) b.dist = dd, b.to = g;
            }
      }
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (want[s] && groups_.find(static_cast<std::uint32_t>(s)) == s && best[s].dist != std::numeric_limits<long>::max())
        joins.push_back({static_cast<std::uint32_t>(s), best[s].to});
    for (const auto& j : joins) unite(j.first, j.second);
  }

  // Rule 8.
  void pockets() {
    const std::uint64_t min = minimum_size(p_.min_pocket_voxels, d_);
    // The main free space: the largest free segment (the first of equals).
    std::size_t main = segs_.size();
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (state_[s] == kFree && (main == segs_.size() || segs_[s].voxels > segs_[main].voxels)) main = s;
    std::vector<char> pocket(segs_.size(), 0);
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (state_[s] == kFree && s != main && segs_[s].voxels < min) {
        pocket[s] = 1;
        state_[s] = kUnknown;  // read as unknown from here on
        changed_ = true;
      }
    std::vector<std::uint32_t> vox;
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      if (!pocket[s]) continue;
      vox.clear();
      box_members(static_cast<std::uint32_t>(s), vox);
      for (const std::uint32_t i : vox)
        for_faces(i, [&](std::size_t j) {
          const std::uint32_t l = labels_[j];
          if (l != s && state_[l] == kUnknown) unite(static_cast<std::uint32_t>(s), l);
        });
    }
    // Small unknown groups next to occupied voxels. Decided for all groups before any join.
    const std::vector<std::uint64_t> size = group_sizes();
    std::vector<std::vector<std::uint32_t>> small(segs_.size());  // member ids at each small group's root
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      const std::uint32_t g = groups_.find(static_cast<std::uint32_t>(s));
      if (state_[s] == kUnknown && size[g] < min) small[g].push_back(static_cast<std::uint32_t>(s));
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> faces;  // (occupied group, shared faces)
    for (std::size_t g = 0; g < segs_.size(); ++g) {
      if (small[g].empty()) continue;
      faces.clear();
      for (const std::uint32_t s : small[g]) {
        vox.clear();
        box_members(s, vox);
        for (const std::uint32_t i : vox)
          for_faces(i, [&](std::size_t j) {
            const std::uint32_t l = labels_[j];
            if (state_[l] == kOccupied) faces.push_back({groups_.find(l), 1});
          });
      }
      if (faces.empty()) continue;
      std::sort(faces.begin(), faces.end());
      std::uint32_t to = faces[0].first, most = 0;
      for (std::size_t a = 0; a < faces.size();) {
        std::size_t b = a;
        while (b < faces.size() && faces[b].first == faces[a].first) ++b;
        if (b - a > most) most = static_cast<std::uint32_t>(b - a), to = faces[a].first;
        a = b;
      }
      joins.push_back({static_cast<std::uint32_t>(g), to});
    }
    // A joined group is occupied from now on (renumber: a group with an occupied member is).
    for (const auto& j : joins) unite(j.first, j.second);
  }

  // Dense ids in the order of the groups' roots (first voxels); each group's statistics combined
  // in id order; the labels of every segment whose id moves rewritten, in increasing old id (a
  // new id is never above its old one, so no rewritten label is read as an old one later).
  void renumber() {
    const std::size_t S = segs_.size();
    std::vector<std::uint8_t> gstate(S, 0);
    for (std::size_t s = 0; s < S; ++s) {
      const std::uint32_t g = groups_.find(static_cast<std::uint32_t>(s));
      if (g == s) gstate[g] = state_[s];
    }
    for (std::size_t s = 0; s < S; ++s)  // a group holding occupied members is occupied
      if (state_[s] == kOccupied) gstate[groups_.find(static_cast<std::uint32_t>(s))] = kOccupied;
    std::vector<std::uint32_t> new_id(S);
    std::vector<Segment> out;
    for (std::size_t s = 0; s < S; ++s) {
      const std::uint32_t g = groups_.find(static_cast<std::uint32_t>(s));
      if (g == s) {
        new_id[s] = static_cast<std::uint32_t>(out.size());
        Segment seg;
        seg.id = new_id[s];
        seg.state = static_cast<State>(gstate[s]);
        seg.bbox_min.fill(std::numeric_limits<std::uint32_t>::max());
        out.push_back(seg);
      } else {
        new_id[s] = new_id[g];  // g < s: numbered already
      }
    }
    std::vector<double> mop_sum(out.size(), 0), c_sum(3 * out.size(), 0);
    for (std::size_t s = 0; s < S; ++s) {
      Segment& t = out[new_id[s]];
      const Segment& m = segs_[s];
      const double v = static_cast<double>(m.voxels);
      t.voxels += m.voxels;
      mop_sum[t.id] += m.mop * v;
      for (int k = 0; k < 3; ++k) {
        t.bbox_min[k] = std::min(t.bbox_min[k], m.bbox_min[k]);
        t.bbox_max[k] = std::max(t.bbox_max[k], m.bbox_max[k]);
        c_sum[3 * t.id + k] += m.centroid[k] * v;
      }
    }
    for (Segment& t : out) {
      const double v = static_cast<double>(t.voxels);
      t.mop = mop_sum[t.id] / v;
      for (int k = 0; k < 3; ++k) t.centroid[k] = c_sum[3 * t.id + k] / v;
    }
    // Single-member groups keep their statistics exactly (no rounding through the weighted sums).
    std::vector<std::uint32_t> members(out.size(), 0);
    for (std::size_t s = 0; s < S; ++s) ++members[new_id[s]];
    for (std::size_t s = 0; s < S; ++s)
      if (members[new_id[s]] == 1) {
        const std::uint32_t id = new_id[s];
        const State st = out[id].state;
        out[id] = segs_[s];
        out[id].id = id;
        out[id].state = st;
      }
    // Labels.
    std::size_t boxes = 0;
    for (std::size_t s = 0; s < S; ++s)
      if (new_id[s] != s) boxes += box_volume(segs_[s]);
    if (2 * boxes > labels_.size()) {
      parallel_for(labels_.size(), p_.threads, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) labels_[i] = new_id[labels_[i]];
      });
    } else {
      for (std::size_t s = 0; s < S; ++s) {
        if (new_id[s] == s) continue;
        const Segment& seg = segs_[s];
        const std::uint32_t from = static_cast<std::uint32_t>(s), to = new_id[s];
        for (std::size_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
          for (std::size_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
            std::uint32_t* row = labels_.data() + nx * (y + ny * z);
            for (std::size_t x = seg.bbox_min[0]; x <= seg.bbox_max[0]; ++x)
              if (row[x] == from) row[x] = to;
          }
      }
    }
    segs_ = std::move(out);
  }

  const Dims d_;
  const std::size_t nx, ny, nz, sz;
  LabelArray& labels_;
  std::vector<Segment>& segs_;
  const Params& p_;
  const std::vector<std::uint64_t>* band_;  // per old id: voxels the surface band added, or nullptr
  Groups groups_;
  std::vector<std::uint8_t> state_;  // per old id: its state (pockets read as unknown once chosen)
  bool changed_ = false;
};

}  // namespace

void group_objects(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                   const std::vector<std::uint64_t>* band_voxels) {
  if (segments.size() < 2) return;
  Grouper(grid, labels, segments, params, band_voxels).run();
}

void assign_kinds(std::vector<Segment>& segments, const Params& params, const Dims& dims) {
  const std::uint64_t min = minimum_size(params.min_object_voxels, dims);
  for (Segment& s : segments) {
    if (s.state == State::free) s.kind = Kind::free;
    else if (s.state == State::unknown) s.kind = Kind::unknown;
    else if (s.kind == Kind::structure) continue;
    else s.kind = s.voxels < min ? Kind::clutter : Kind::object;
  }
}

}  // namespace occseg
