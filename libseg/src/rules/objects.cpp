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
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();  // no segment
using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

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
      : d_(g.dims), nx(d_.nx), ny(d_.ny), nz(d_.nz), sz(nx * ny), nx32_(static_cast<std::uint32_t>(nx)),
        ny32_(static_cast<std::uint32_t>(ny)), labels_(labels), segs_(segs), p_(p), band_(band),
        groups_(segs.size()), state_(segs.size()) {
    for (std::size_t s = 0; s < segs.size(); ++s) state_[s] = static_cast<std::uint8_t>(segs[s].state);
  }

  void run() {
    const std::size_t S = segs_.size();
    // The states before rule 8 turns pockets unknown: rule 6's paths are through unknown voxels.
    occ_.assign(S, 0);
    unk_.assign(S, 0);
    for (std::size_t s = 0; s < S; ++s) {
      occ_[s] = state_[s] == kOccupied;
      unk_[s] = state_[s] == kUnknown;
    }
    const bool near = p_.object_gap > 0 && proximity_applies();
    if (p_.min_pocket_voxels > 0) choose_pockets();
    // Rule 8's joins of pockets to unknown segments are made in the visit, before rules 6 and 7:
    // they join unknown segments only, and those two rules read and join occupied groups only.
    const bool from_unknown = near && seeds_from_unknown();
    visit_faces(from_unknown);
    if (near) proximity(from_unknown);
    if (p_.min_object_voxels > 0) speckles();
    if (p_.min_pocket_voxels > 0) pockets();
    if (changed_) renumber();
  }

 private:
  // Calls fn(i, x, y, z) for the voxels of the segments flagged in `want` (by id), in scan order
  // within each segment's box, segment after segment in id order; in one pass over the labels
  // instead when the boxes add up to more than half the map. Nothing is listed: on a noisy map the
  // occupied voxels are a third of the map.
  template <typename Fn>
  void for_members(const std::vector<char>& want, Fn&& fn) const {
    std::size_t boxes = 0;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (want[s]) boxes += box_volume(segs_[s]);
    if (2 * boxes > labels_.size()) {
      for (std::size_t z = 0; z < nz; ++z)
        for (std::size_t y = 0; y < ny; ++y) {
          const std::size_t row = nx * (y + ny * z);
          for (std::size_t x = 0; x < nx; ++x) {
            const std::uint32_t l = labels_[row + x];
            if (l < want.size() && want[l]) fn(row + x, x, y, z);  // (rule 6's marked labels are >= S)
          }
        }
      return;
    }
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (want[s]) for_box(static_cast<std::uint32_t>(s), fn);
  }

  // for_members() in up to kPieces pieces of the map's planes or of the segments, run on the
  // threads: fn(out[piece], i, x, y, z), out resized to the pieces. What a piece finds never
  // depends on the thread count.
  static constexpr std::size_t kPieces = 64;
  template <typename Out, typename Fn>
  void for_members_in_pieces(const std::vector<char>& want, std::vector<Out>& out, Fn&& fn) const {
    std::size_t boxes = 0;
    std::vector<std::uint32_t> list;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (want[s]) boxes += box_volume(segs_[s]), list.push_back(static_cast<std::uint32_t>(s));
    const bool scan = 2 * boxes > labels_.size();
    const std::size_t items = scan ? nz : list.size(), pieces = std::min(kPieces, items);
    out.assign(pieces, Out());
    parallel_for_dynamic(pieces, p_.threads, [&](std::size_t p0, std::size_t p1) {
      for (std::size_t p = p0; p < p1; ++p) {
        Out& o = out[p];
        const std::size_t b = items * p / pieces, e = items * (p + 1) / pieces;
        if (scan) {
          for (std::size_t z = b; z < e; ++z)
            for (std::size_t y = 0; y < ny; ++y) {
              const std::size_t row = nx * (y + ny * z);
              for (std::size_t x = 0; x < nx; ++x) {
                const std::uint32_t l = label_at(row + x);
                if (l < want.size() && want[l]) fn(o, row + x, x, y, z);  // (rule 6's marked labels are >= S)
              }
            }
        } else {
          for (std::size_t k = b; k < e; ++k)
            for_box(list[k], [&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) { fn(o, i, x, y, z); });
        }
      }
    });
  }

  // Calls fn(i, x, y, z) for the voxels of segment s, in scan order within its box.
  template <typename Fn>
  void for_box(std::uint32_t s, Fn&& fn) const {
    const Segment& seg = segs_[s];
    for (std::size_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
      for (std::size_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
        const std::size_t row = nx * (y + ny * z);
        for (std::size_t x = seg.bbox_min[0]; x <= seg.bbox_max[0]; ++x)
          if (label_at(row + x) == s) fn(row + x, x, y, z);
      }
  }

  // Voxel i's label, read atomically: rule 6 marks labels on the threads while others scan.
  std::uint32_t label_at(std::size_t i) const { return __atomic_load_n(&labels_[i], __ATOMIC_RELAXED); }

  // Calls fn(j) for each 6-neighbour j of voxel i = (x, y, z) inside the map.
  template <typename Fn>
  void for_faces(std::size_t i, std::size_t x, std::size_t y, std::size_t z, Fn&& fn) const {
    if (x > 0) fn(i - 1);
    if (x + 1 < nx) fn(i + 1);
    if (y > 0) fn(i - nx);
    if (y + 1 < ny) fn(i + nx);
    if (z > 0) fn(i - sz);
    if (z + 1 < nz) fn(i + sz);
  }
  // The same from the index alone (voxel indices fit 32 bits: the labels hold them).
  template <typename Fn>
  void for_faces(std::size_t i, Fn&& fn) const {
    const std::uint32_t q = static_cast<std::uint32_t>(i) / nx32_, z = q / ny32_;
    for_faces(i, i - std::size_t(q) * nx, q - z * ny32_, z, fn);
  }

  void unite(std::uint32_t a, std::uint32_t b) { changed_ |= groups_.unite(a, b); }

  // Rule 6 has something to join: two occupied segments and an unknown voxel.
  bool proximity_applies() const {
    std::size_t occupied = 0;
    bool unknown = false;
    for (std::size_t s = 0; s < segs_.size(); ++s) occupied += occ_[s], unknown = unknown || unk_[s];
    return occupied >= 2 && unknown;
  }

  // Whether rule 6's seeds are cheaper found from the unknown voxels' faces than from the
  // occupied ones' (the boxes, or the map, read; six faces per voxel).
  bool seeds_from_unknown() const {
    const std::size_t n = labels_.size();
    std::size_t occ_boxes = 0, unk_boxes = 0;
    std::uint64_t occ_voxels = 0, unk_voxels = 0;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (occ_[s]) occ_boxes += box_volume(segs_[s]), occ_voxels += segs_[s].voxels;
      else if (unk_[s]) unk_boxes += box_volume(segs_[s]), unk_voxels += segs_[s].voxels;
    const auto cost = [&](std::size_t boxes, std::uint64_t voxels) {
      return 2 * boxes > n ? n + 6 * voxels : boxes + 6 * voxels;
    };
    return cost(unk_boxes, unk_voxels) < cost(occ_boxes, occ_voxels);
  }

  // Rule 8's pockets: every free segment but the largest (the first of equals) with fewer than
  // the minimum voxels; read as unknown from here on, except by rule 6.
  void choose_pockets() {
    pocket_min_ = minimum_size(p_.min_pocket_voxels, d_);
    pocket_.assign(segs_.size(), 0);
    std::size_t main = segs_.size();
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (state_[s] == kFree && (main == segs_.size() || segs_[s].voxels > segs_[main].voxels)) main = s;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (state_[s] == kFree && s != main && segs_[s].voxels < pocket_min_) {
        pocket_[s] = 1;
        state_[s] = kUnknown;
        changed_ = true;
      }
  }

  // One visit, in id order (the order of their first voxels in the map), of the segments whose
  // faces rules 6 and 8 read:
  //  - rule 6 (from_unknown): the unknown segments; an unknown voxel beside occupied ones is a
  //    seed (seeds_, kept_: the first occupied segment beside it), and joins them all;
  //  - rule 8: a pocket joins the unknown segments (pockets included) beside it; and the faces of
  //    every unknown segment or pocket of fewer than the minimum voxels (only those can be in a
  //    small group) with occupied segments are counted (faces_, listed by segment in face_at_).
  void visit_faces(bool from_unknown) {
    const bool pockets = p_.min_pocket_voxels > 0;
    const std::size_t S = segs_.size();
    std::vector<char> want(S, 0);
    bool any = false;
    for (std::size_t s = 0; s < S; ++s) {
      const bool small = pockets && (unk_[s] || pocket_[s]) && segs_[s].voxels < pocket_min_;
      want[s] = (from_unknown && unk_[s]) || small || (pockets && pocket_[s]);
      any = any || want[s];
    }
    if (pockets) face_at_.assign(S + 1, 0);
    if (!any) return;
    // In pieces on the threads; each piece's findings are taken in piece order afterwards.
    struct Found {
      std::vector<Seed> seeds;
      std::vector<Face> faces;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    };
    std::vector<Found> found;
    for_members_in_pieces(want, found, [&](Found& out, std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
      const std::uint32_t s = labels_[i];
      const bool seeds = from_unknown && unk_[s];
      const bool count = pockets && segs_[s].voxels < pocket_min_;
      const bool join = pockets && pocket_[s];
      std::uint32_t a = kNone;
      for_faces(i, x, y, z, [&](std::size_t j) {
        const std::uint32_t l = labels_[j];
        if (occ_[l]) {
          if (seeds) {
            if (a == kNone) a = l;
            else if (l != a) out.joins.push_back({a, l});
          }
          if (count) {
            if (!out.faces.empty() && out.faces.back().segment == s && out.faces.back().occupied == l) ++out.faces.back().count;
            else out.faces.push_back({s, l, 1});
          }
        } else if (join && l != s && (unk_[l] || pocket_[l])) {
          // (runs of one neighbour: one join)
          if (out.joins.empty() || out.joins.back() != std::make_pair(s, l)) out.joins.push_back({s, l});
        }
      });
      if (a != kNone) {
        out.seeds.push_back({static_cast<std::uint32_t>(i), s, a});
      }
    });
    // (The lists are sized once and each piece's freed as soon as it is taken: the seeds and the
    // faces of a noisy map are a few MB, and grown or copied whole they were there twice.)
    std::size_t nfaces = 0, nseeds = 0;
    for (const Found& f : found) nfaces += f.faces.size(), nseeds += f.seeds.size();
    seeds_.reserve(seeds_.size() + nseeds);
    for (Found& f : found) {
      for (const auto& j : f.joins) unite(j.first, j.second);
      f.joins = {};
      seeds_.insert(seeds_.end(), f.seeds.begin(), f.seeds.end());
      f.seeds = {};
    }
    if (!pockets) return;
    // Listed by segment (a stable counting sort: a visit of the map in one pass meets them mixed).
    for (const Found& f : found)
      for (const Face& e : f.faces) ++face_at_[e.segment + 1];
    for (std::size_t s = 0; s < S; ++s) face_at_[s + 1] += face_at_[s];
    faces_.resize(nfaces);
    std::vector<std::uint32_t> at(face_at_.begin(), face_at_.end() - 1);
    for (Found& f : found) {
      for (const Face& e : f.faces) faces_[at[e.segment]++] = e;
      f.faces = {};
    }
  }

  // Rule 6. A path of unknown voxels lies inside one unknown segment (a 6-connected region of
  // unknown voxels), so the rule works per unknown segment U on its seeds, the voxels of U beside
  // occupied ones:
  //  1. Every seed joins the occupied segments beside it (a path of one unknown voxel). The seeds
  //     are found from whichever side costs less: the occupied voxels' faces, or the unknown
  //     ones' (visit_faces).
  //  2. A U whose seeds all lie beside one group after that joins nothing more. A U of at most
  //     object_gap voxels joins every group beside it: any two of its voxels are linked inside it
  //     by at most that many.
  //  3. In the other U, a breadth-first search from the seeds to depth object_gap - 1 keeps for
  //     each voxel reached its distance d (the unknown voxels on a shortest path from an occupied
  //     one, itself included) and one segment at that distance. Two segments are joined where
  //     the waves of two meet: at two neighbouring voxels with d(u) + d(v) <= object_gap (the
  //     meetings beside occupied voxels, d = 1, are step 1's). Every join stands for a path of
  //     at most object_gap unknown voxels; and along any such path between segments A and B the
  //     segments the search kept change only at such meetings, so A and B end up in one group:
  //     the groups are exactly the closure of "a path of at most object_gap unknown voxels",
  //     whichever segment a tie kept and in whatever order the seeds were found.
  // The labels of the voxels searched (and, found from the occupied side, of every seed) hold the
  // kept segment and their d during the search, as kept | d << b (LabelMarks: 2^b >= S segments,
  // d at most object_gap <= 16, so it fits 32 bits unless S is above about 2^27, when d has an
  // array of its own, ArrayMarks), and get theirs back after it. Marked labels are at least 2^b
  // >= S, so no scan takes them for a segment's; and no scratch the size of the map is allocated
  // and cleared. With marks in the labels, steps 1 (from the occupied side) and 3 run on the
  // threads, each voxel marked by one compare-and-swap: which segment a voxel keeps may then
  // depend on timing, the groups (the closure above) do not.
  struct LabelMarks {
    std::uint32_t* labels;
    unsigned b;
    // d of voxel j (0: not reached) and, when reached, its kept segment.
    std::uint32_t get(std::size_t j, std::uint32_t& kept) const {
      const std::uint32_t l = labels[j], d = l >> b;
      kept = l & ((std::uint32_t(1) << b) - 1);
      return d;
    }
    void set(std::size_t j, std::uint32_t d, std::uint32_t kept) { labels[j] = kept | d << b; }
  };
  struct ArrayMarks {
    std::uint32_t* labels;
    std::unique_ptr<std::uint8_t, void (*)(void*)> dist;
    explicit ArrayMarks(std::uint32_t* l, std::size_t n) : labels(l), dist(static_cast<std::uint8_t*>(std::calloc(n, 1)), std::free) {
      if (!dist) throw std::bad_alloc();
    }
    std::uint32_t get(std::size_t j, std::uint32_t& kept) const {
      const std::uint32_t d = dist.get()[j];
      if (d) kept = labels[j];
      return d;
    }
    void set(std::size_t j, std::uint32_t d, std::uint32_t kept) {
      dist.get()[j] = static_cast<std::uint8_t>(d);
      labels[j] = kept;
    }
  };

  void proximity(bool from_unknown) {
    const std::uint64_t S = segs_.size();
    unsigned b = 0;
    while ((std::uint64_t(1) << b) < S) ++b;
    if ((static_cast<std::uint64_t>(p_.object_gap) + 1) << b <= std::uint64_t(1) << 32) {
      LabelMarks m{labels_.data(), b};
      proximity(from_unknown, m);
    } else {
      ArrayMarks m(labels_.data(), labels_.size());
      proximity(from_unknown, m);
    }
  }

  template <typename Marks>
  void proximity(bool from_unknown, Marks& m) {
    const std::size_t S = segs_.size();
    const int gap = p_.object_gap;
    // (voxel whose label holds a kept segment, its own label), in parts (each piece's, as found)
    std::vector<Pairs> saved;
    if (!from_unknown) seeds_from_occupied(m, saved);
    // Step 2: per unknown segment, the group of its first seed and whether another one is beside it.
    std::vector<std::uint32_t> first(S, kNone);
    std::vector<char> several(S, 0);
    for (const Seed& e : seeds_) {
      const std::uint32_t g = groups_.find(e.kept);
      if (first[e.segment] == kNone) first[e.segment] = g;
      else if (first[e.segment] != g) several[e.segment] = 1;
    }
    std::vector<std::uint32_t> next;
    for (const Seed& e : seeds_) {
      if (!several[e.segment]) continue;
      if (segs_[e.segment].voxels <= static_cast<std::uint64_t>(gap)) {
        unite(first[e.segment], e.kept);
      } else {
        if (from_unknown) {  // (from the occupied side the seeds are marked already)
          if (saved.empty()) saved.emplace_back();
          saved.back().push_back({e.voxel, e.segment});
          m.set(e.voxel, 1, e.kept);
        }
        next.push_back(e.voxel);
      }
    }
    seeds_ = std::vector<Seed>();
    // Step 3 (the seeds of other unknown segments are never next to a voxel reached: their marks,
    // set by the search from the occupied side, are never read).
    search_gaps(m, next, saved);
    parallel_for_dynamic(saved.size(), p_.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t q = b; q < e; ++q)
        for (const auto& sv : saved[q]) labels_[sv.first] = sv.second;  // (each voxel once)
    });
  }

  // Step 1 of rule 6 from the occupied voxels, on the threads: the unknown voxels beside them are
  // the seeds, each marked once (a compare-and-swap on its label) with the first occupied
  // segment among its faces (for_faces()' order) and joining the others. Its own faces decide the
  // mark, so whichever thread marks a seed writes the same one; labels are read with atomic
  // loads, as other seeds are marked meanwhile.
  void seeds_from_occupied(LabelMarks& m, std::vector<Pairs>& saved) {
    const unsigned b = m.b;
    std::uint32_t* const l = m.labels;
    struct Found {
      std::vector<Seed> seeds;
      Pairs joins;
    };
    std::vector<Found> found;
    for_members_in_pieces(occ_, found, [&](Found& out, std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
      for_faces(i, x, y, z, [&](std::size_t j) {
        std::uint32_t lj = label_at(j);
        if ((lj >> b) != 0 || !unk_[lj]) return;  // (a seed already, or not unknown)
        std::uint32_t a = kNone;
        const std::size_t joins = out.joins.size();
        for_faces(j, [&](std::size_t q) {
          const std::uint32_t lq = label_at(q);  // (occupied voxels are never marked)
          if ((lq >> b) != 0 || !occ_[lq]) return;
          if (a == kNone) a = lq;
          else if (lq != a) out.joins.push_back({a, lq});
        });
        if (__atomic_compare_exchange_n(&l[j], &lj, a | std::uint32_t(1) << b, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED))
          out.seeds.push_back({static_cast<std::uint32_t>(j), lj, a});
        else
          out.joins.resize(joins);  // (the thread that marked it has the same joins)
      });
    });
    std::size_t n = 0;
    for (const Found& f : found) n += f.seeds.size();
    seeds_.reserve(seeds_.size() + n);
    for (Found& f : found) {
      for (const auto& j : f.joins) unite(j.first, j.second);
      Pairs part;
      part.reserve(f.seeds.size());
      for (const Seed& e : f.seeds) seeds_.push_back(e), part.push_back({e.voxel, e.segment});
      saved.push_back(std::move(part));
      f = Found();
    }
  }
  // The same in one scan, the first segment to reach a seed kept (2^b above about 2^27 segments:
  // a seed's label holds its kept segment meanwhile, so the scan must not take it for one of
  // that segment's voxels).
  void seeds_from_occupied(ArrayMarks& m, std::vector<Pairs>& saved) {
    saved.emplace_back();
    for_members(occ_, [&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
      std::uint32_t a = 0;
      if (m.get(i, a)) return;
      a = labels_[i];
      for_faces(i, x, y, z, [&](std::size_t j) {
        std::uint32_t k = 0;
        if (m.get(j, k)) {
          if (k != a) unite(a, k);
        } else if (unk_[labels_[j]]) {
          seeds_.push_back({static_cast<std::uint32_t>(j), labels_[j], a});
          saved.back().push_back({static_cast<std::uint32_t>(j), labels_[j]});
          m.set(j, 1, a);
        }
      });
    });
  }

  // Step 3 of rule 6 on the threads, one depth at a time, the layer in pieces: a voxel is taken
  // by whichever wave reaches it first (one compare-and-swap on its label), the others meeting
  // it there. Each piece's voxels taken are the next layer's part and a part of `saved` as they
  // are (not gathered into one list: that held them twice).
  void search_gaps(LabelMarks& m, std::vector<std::uint32_t>& seeds, std::vector<Pairs>& saved) {
    const int gap = p_.object_gap;
    const unsigned b = m.b;
    const std::uint32_t mask = (std::uint32_t(1) << b) - 1;
    std::uint32_t* const l = m.labels;
    struct Wave {
      const std::uint32_t *from = nullptr, *to = nullptr;  // its stretch of the layer
      std::vector<std::uint32_t> next;
      Pairs saved, joins;
    };
    std::vector<std::vector<std::uint32_t>> layer, parts;
    parts.push_back(std::move(seeds));
    std::vector<Wave> waves;
    for (int depth = 1; depth < gap; ++depth) {
      layer.swap(parts);
      parts.clear();
      std::size_t total = 0;
      for (const auto& part : layer) total += part.size();
      if (total == 0) break;
      const bool grow = depth + 1 < gap;
      const std::uint32_t marked = static_cast<std::uint32_t>(depth + 1) << b;
      const std::size_t chunk = std::max<std::size_t>(4096, (total + kPieces - 1) / kPieces);
      waves.clear();
      for (const auto& part : layer)
        for (std::size_t o = 0; o < part.size(); o += chunk) {
          waves.emplace_back();
          waves.back().from = part.data() + o;
          waves.back().to = part.data() + std::min(part.size(), o + chunk);
        }
      parallel_for_dynamic(waves.size(), p_.threads, [&](std::size_t p0, std::size_t p1) {
        for (std::size_t p = p0; p < p1; ++p) {
          Wave& w = waves[p];
          for (const std::uint32_t* up = w.from; up != w.to; ++up) {
            const std::uint32_t u = *up;
            const std::uint32_t a = __atomic_load_n(&l[u], __ATOMIC_RELAXED) & mask;  // (set at an earlier depth)
            for_faces(u, [&](std::size_t j) {
              std::uint32_t lj = __atomic_load_n(&l[j], __ATOMIC_RELAXED);
              for (;;) {
                if (const std::uint32_t dj = lj >> b) {
                  const std::uint32_t k = lj & mask;
                  if (k != a && depth + static_cast<int>(dj) <= gap &&
                      (w.joins.empty() || w.joins.back() != std::make_pair(a, k)))
                    w.joins.push_back({a, k});
                  return;
                }
                if (!grow || !unk_[lj]) return;
                if (__atomic_compare_exchange_n(&l[j], &lj, a | marked, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
                  w.saved.push_back({static_cast<std::uint32_t>(j), lj});
                  w.next.push_back(static_cast<std::uint32_t>(j));
                  return;
                }
              }
            });
          }
        }
      });
      for (Wave& w : waves) {
        for (const auto& j : w.joins) unite(j.first, j.second);
        if (!w.saved.empty()) saved.push_back(std::move(w.saved));
        if (!w.next.empty()) parts.push_back(std::move(w.next));
      }
      waves.clear();
      layer.clear();
    }
  }
  // The same on one thread.
  void search_gaps(ArrayMarks& m, std::vector<std::uint32_t>& next, std::vector<Pairs>& saved) {
    const int gap = p_.object_gap;
    std::vector<std::uint32_t> layer;
    saved.emplace_back();
    for (int depth = 1; depth < gap && !next.empty(); ++depth) {
      layer.swap(next);
      next.clear();
      for (const std::uint32_t u : layer) {
        std::uint32_t a = 0;
        m.get(u, a);
        for_faces(u, [&](std::size_t j) {
          std::uint32_t k = 0;
          if (const std::uint32_t dj = m.get(j, k)) {
            if (k != a && depth + static_cast<int>(dj) <= gap) unite(a, k);
          } else if (depth + 1 < gap && unk_[labels_[j]]) {
            saved.back().push_back({static_cast<std::uint32_t>(j), labels_[j]});
            m.set(j, static_cast<std::uint32_t>(depth + 1), a);
            next.push_back(static_cast<std::uint32_t>(j));
          }
        });
      }
    }
  }

  // Voxels per group (at the roots); `evidence`: leaving out those the surface band added.
  std::vector<std::uint64_t> group_sizes(bool evidence = false) {
    std::vector<std::uint64_t> size;
    group_sizes_into(size, evidence);
    return size;
  }
  void group_sizes_into(std::vector<std::uint64_t>& size, bool evidence) {
    size.assign(segs_.size(), 0);
    for (std::size_t s = 0; s < segs_.size(); ++s)
      size[groups_.find(static_cast<std::uint32_t>(s))] += segs_[s].voxels - (evidence && band_ ? (*band_)[s] : 0);
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
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      if (!want[s]) continue;
      Best& b = best[groups_.find(static_cast<std::uint32_t>(s))];
      for_box(static_cast<std::uint32_t>(s), [&](std::size_t, std::size_t ux, std::size_t uy, std::size_t uz) {
        const long x = static_cast<long>(ux), y = static_cast<long>(uy), z = static_cast<long>(uz);
        for (long zz = std::max(0L, z - r); zz <= std::min<long>(nz - 1, z + r); ++zz)
          for (long yy = std::max(0L, y - r); yy <= std::min<long>(ny - 1, y + r); ++yy) {
            const std::uint32_t* const row = labels_.data() + nx * (static_cast<std::size_t>(yy) + ny * static_cast<std::size_t>(zz));
            for (long xx = std::max(0L, x - r); xx <= std::min<long>(nx - 1, x + r); ++xx) {
              const std::uint32_t l = row[xx];
              if (state_[l] != kOccupied) continue;
              const std::uint32_t g = groups_.find(l);
              if (size[g] < min) continue;
              const long dd = (xx - x) * (xx - x) + (yy - y) * (yy - y) + (zz - z) * (zz - z);
              if (dd < b.dist || (dd == b.dist && g < b.to)) b.dist = dd, b.to = g;
            }
          }
      });
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    for (std::size_t s = 0; s < segs_.size(); ++s)
      if (want[s] && groups_.find(static_cast<std::uint32_t>(s)) == s && best[s].dist != std::numeric_limits<long>::max())
        joins.push_back({static_cast<std::uint32_t>(s), best[s].to});
    for (const auto& j : joins) unite(j.first, j.second);
  }

  // Rule 8, after choose_pockets() and visit_faces(): small unknown groups next to occupied voxels.
  void pockets() {
    const std::uint64_t min = pocket_min_;
    // Small unknown groups next to occupied voxels. Decided for all groups before any join.
    std::vector<std::uint64_t> size = group_sizes();
    // The members of each small group in id order, listed by root (start: offsets by root).
    std::vector<std::uint32_t> start(segs_.size() + 1, 0), member;
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      const std::uint32_t g = groups_.find(static_cast<std::uint32_t>(s));
      if (state_[s] == kUnknown && size[g] < min) ++start[g + 1];
    }
    for (std::size_t g = 0; g < segs_.size(); ++g) start[g + 1] += start[g];
    member.resize(start[segs_.size()]);
    {
      std::vector<std::uint32_t> at(start.begin(), start.end() - 1);
      for (std::size_t s = 0; s < segs_.size(); ++s) {
        const std::uint32_t g = groups_.find(static_cast<std::uint32_t>(s));
        if (state_[s] == kUnknown && size[g] < min) member[at[g]++] = static_cast<std::uint32_t>(s);
      }
    }
    // Rule 7's speckles that are left (occupied groups of fewer voxels than min_object_voxels, by
    // its evidence count): a group that joins an object also takes the speckles it touches, which
    // would otherwise lie against that object as clutter of their own (each speckle once: the
    // first such group in id order takes it, so no speckle ties two objects together).
    // (Their sizes by rule 7's count go in the array of the sizes above, read no more: the grouping
    // runs at the pipeline's peak, with a segment table of hundreds of thousands on a noisy map.)
    const std::uint64_t speckle_min = p_.min_object_voxels > 0 ? minimum_size(p_.min_object_voxels, d_) : 0;
    if (speckle_min) group_sizes_into(size, /*evidence=*/true);
    const std::vector<std::uint64_t>& occupied_size = size;
    const auto speckle = [&](std::uint32_t root) { return speckle_min && occupied_size[root] < speckle_min; };
    std::vector<char> taken(speckle_min ? segs_.size() : 0, 0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> faces;  // (occupied group, shared faces)
    for (std::size_t g = 0; g < segs_.size(); ++g) {
      if (start[g] == start[g + 1]) continue;
      faces.clear();
      for (std::uint32_t m = start[g]; m < start[g + 1]; ++m)
        for (std::uint32_t f = face_at_[member[m]]; f < face_at_[member[m] + 1]; ++f)
          faces.push_back({groups_.find(faces_[f].occupied), faces_[f].count});
      if (faces.empty()) continue;
      std::sort(faces.begin(), faces.end());
      // The group of the most faces, a speckle only if the group touches nothing else; ties: the
      // smaller id (the first in this order).
      std::uint32_t to = faces[0].first, most = 0;
      bool to_speckle = true;
      for (std::size_t a = 0; a < faces.size();) {
        std::uint32_t count = 0;
        std::size_t b = a;
        for (; b < faces.size() && faces[b].first == faces[a].first; ++b) count += faces[b].second;
        const bool small = speckle(faces[a].first);
        if ((to_speckle && !small) || (small == to_speckle && count > most)) most = count, to = faces[a].first, to_speckle = small;
        a = b;
      }
      joins.push_back({static_cast<std::uint32_t>(g), to});
      for (std::size_t a = 0; a < faces.size(); ++a) {
        const std::uint32_t o = faces[a].first;
        if (o != to && speckle(o) && !taken[o]) taken[o] = 1, joins.push_back({o, to});
      }
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
      // The moved segments' boxes, in id order within each band of planes, the bands on the
      // threads: a voxel is rewritten only by its own segment, to an id below every later one's
      // (new_id[s] <= s), so a band ends as one pass over the map in id order leaves it. Each
      // band lists the moved segments whose boxes reach it (in id order).
      const std::size_t bands = std::min<std::size_t>(nz, 32);
      const auto band_start = [&](std::size_t b) { return b * nz / bands; };  // band b: [start(b), start(b + 1))
      std::vector<std::uint32_t> band_of(nz);
      for (std::size_t b = 0; b < bands; ++b)
        for (std::size_t z = band_start(b); z < band_start(b + 1); ++z) band_of[z] = static_cast<std::uint32_t>(b);
      std::vector<std::vector<std::uint32_t>> in_band(bands);
      for (std::size_t s = 0; s < S; ++s)
        if (new_id[s] != s && segs_[s].voxels > 0)  // (an empty one has no box)
          for (std::size_t b = band_of[segs_[s].bbox_min[2]]; b <= band_of[segs_[s].bbox_max[2]]; ++b)
            in_band[b].push_back(static_cast<std::uint32_t>(s));
      std::uint32_t* const l = labels_.data();
      parallel_for_dynamic(bands, p_.threads, [&](std::size_t b0, std::size_t b1) {
        for (std::size_t b = b0; b < b1; ++b)
          for (const std::uint32_t from : in_band[b]) {
            // (The box in locals: the label stores could alias the table's 32-bit fields.)
            const Segment& seg = segs_[from];
            const std::uint32_t to = new_id[from];
            const std::size_t x0 = seg.bbox_min[0], x1 = std::size_t{seg.bbox_max[0]} + 1, y0 = seg.bbox_min[1],
                              y1 = std::size_t{seg.bbox_max[1]} + 1;
            const std::size_t za = std::max<std::size_t>(seg.bbox_min[2], band_start(b)),
                              zb = std::min<std::size_t>(std::size_t{seg.bbox_max[2]} + 1, band_start(b + 1));
            for (std::size_t z = za; z < zb; ++z)
              for (std::size_t y = y0; y < y1; ++y) {
                std::uint32_t* row = l + nx * (y + ny * z);
                for (std::size_t x = x0; x < x1; ++x)
                  if (row[x] == from) row[x] = to;
              }
          }
      });
    }
    segs_ = std::move(out);
  }

  const Dims d_;
  const std::size_t nx, ny, nz, sz;
  const std::uint32_t nx32_, ny32_;
  LabelArray& labels_;
  std::vector<Segment>& segs_;
  const Params& p_;
  const std::vector<std::uint64_t>* band_;  // per old id: voxels the surface band added, or nullptr
  Groups groups_;
  std::vector<std::uint8_t> state_;  // per old id: its state (pockets read as unknown once chosen)
  std::vector<char> occ_, unk_;      // per old id: occupied, unknown (before rule 8)
  std::vector<char> pocket_;         // per old id: a pocket (rule 8)
  std::uint64_t pocket_min_ = 0;
  struct Face {
    std::uint32_t segment, occupied, count;  // faces between an unknown segment (or pocket) and an occupied one
  };
  std::vector<Face> faces_;              // of the small unknown segments and pockets, by segment
  std::vector<std::uint32_t> face_at_;   // faces_ of segment s: [face_at_[s], face_at_[s + 1])
  struct Seed {
    std::uint32_t voxel, segment, kept;  // an unknown voxel beside occupied ones, its segment, one of those
  };
  std::vector<Seed> seeds_;  // rule 6's, in the order found
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
