// Structure and objects (rules/structure.hpp): several planes per segment, the objects standing on
// or against them, and the coplanar fragments of a surface.
#include "rules/structure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

#include "occseg/parallel.hpp"
#include "rules/box_rows.hpp"
#include "rules/neighbours.hpp"
#include "rules/objects.hpp"
#include "rules/planes.hpp"

namespace occseg {

namespace {

using Vec = std::array<double, 3>;

// A structural piece sags by less than this (voxel edges) across its extent (examine()).
constexpr double kMaxSag = 0.5;
// A segment is examined when at least this share (per cent) of a sample of its voxels is thin
// along some axis (examine()).
constexpr std::size_t kMinSurfacePercent = 50;
// An occupied segment that is not structure (and no fragment of a piece) joins a structural piece's
// segment when at least this share (per cent) of its voxels lie within one voxel edge of the
// piece's plane (attract_fragments(); docs/algorithm.md rule 11, "Coplanar segments").
constexpr std::size_t kCoplanarPercent = 80;

Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Two unit vectors spanning the plane of normal n (n x e for the axis e least aligned with n, then
// n x that): for an axis-aligned plane they are the other two axes.
void plane_basis(const Vec& n, Vec& u, Vec& v) {
  int a = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(n[k]) < std::fabs(n[a])) a = k;
  Vec e{0, 0, 0};
  e[a] = 1;
  u = cross(n, e);
  const double len = std::sqrt(dot(u, u));
  for (double& c : u) c /= len;
  v = cross(n, u);
}

// A piece of a plane found in a segment: its voxels' extent along the plane's axes.
struct Piece {
  std::uint32_t segment = 0;
  Plane pl;
  Vec u{}, v{};
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
  std::array<std::uint32_t, 3> lo{}, hi{};  // box of its voxels
  std::size_t voxels = 0;
  std::uint64_t voxel = 0;  // its first inlier (a voxel index)
  int axis = 2;  // the orientation it was searched in (examine()): its normal is within 45 degrees of it
  bool structural = false;
  double min_height = 0;      // max(kMinObjectHeight, kNoiseHeights x sigma)
  bool open[2] = {false, false};  // along +n, -n: the side sees free space
};

struct Sum {
  std::uint64_t n = 0;
  double p = 0, c[3] = {0, 0, 0};
  std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u}, hi{0, 0, 0};
  void add(const Vec& q, double value) {
    ++n;
    p += value;
    for (int k = 0; k < 3; ++k) {
      const auto x = static_cast<std::uint32_t>(q[k]);
      c[k] += q[k];
      lo[k] = std::min(lo[k], x);
      hi[k] = std::max(hi[k], x);
    }
  }
  void store(Segment& seg) const {
    seg.voxels = n;
    seg.mop = p / double(n);
    seg.bbox_min = lo;
    seg.bbox_max = hi;
    for (int k = 0; k < 3; ++k) seg.centroid[k] = c[k] / double(n);
  }
};

class Structure {
 public:
  Structure(const Grid& g, LabelArray& labels, std::vector<Segment>& segs, const Params& p, const kernels::Table& k)
      : g_(g), d_(g.dims), labels_(labels), segs_(segs), p_(p), k_(k),
        neighbours_(g.dims, p.occupied_connectivity == 26) {
    min_plane_ = static_cast<std::size_t>(p.support_plane);
    min_object_ = std::max<std::size_t>(kMinObjectVoxels, minimum_size(p.min_object_voxels, d_));
    extent_ = p.structure_extent / g.voxel_size;
    cell_ = std::max(2, p.object_gap);
    margin_ = p.object_gap + 1;
  }

  void run(std::vector<PlanePiece>* out) {
    const std::size_t original = segs_.size();
    std::vector<std::uint32_t> candidates;
    std::size_t boxes = 0;
    for (std::size_t s = 0; s < original; ++s) {
      const Segment& seg = segs_[s];
      if (seg.state != State::occupied || seg.kind == Kind::structure || seg.voxels < 2 * min_plane_) continue;
      if (original + 2 * seg.voxels + 2 >= kTop) continue;  // room for the temporary labels
      candidates.push_back(static_cast<std::uint32_t>(s));
      boxes += box_volume(seg);
    }
    // The candidates' voxels, by a scan of each one's box, or when the boxes add up to more than
    // the map, bucketed in one pass over the labels (a building's shell spans the whole map). A
    // split relabels only the voxels of the segment being split, so buckets stay valid.
    std::vector<std::uint32_t> bucket;
    std::vector<std::size_t> start(candidates.size() + 1, 0);
    if (boxes > labels_.size()) {
      std::vector<std::uint32_t> slot(original, ~0u);
      for (std::size_t c = 0; c < candidates.size(); ++c) {
        slot[candidates[c]] = static_cast<std::uint32_t>(c);
        start[c + 1] = start[c] + segs_[candidates[c]].voxels;
      }
      bucket.resize(start.back());
      std::vector<std::size_t> fill(start.begin(), start.end() - 1);
      for (std::size_t i = 0; i < labels_.size(); ++i) {
        const std::uint32_t c = slot[labels_[i]];
        if (c != ~0u) bucket[fill[c]++] = static_cast<std::uint32_t>(i);
      }
    }
    // The searches only read the labels and their own segment's entry, and a split relabels only
    // the voxels of the segment it splits (to ids no other candidate has): so consecutive
    // candidates are searched side by side, each by an examiner of its own, then split one after
    // the other in order, exactly as one at a time. A batch holds candidates of at most
    // max(largest candidate, map / 256) voxels together, so its examiners' scratch (about 80
    // bytes per voxel examined) stays within the largest one's or a third of a byte per voxel.
    // (A lone search counts its box's rows on the threads; those of a batch share them.)
    const auto search_one = [&](Structure& e, std::size_t c, int threads) {
      e.search(candidates[c], bucket.empty() ? nullptr : bucket.data() + start[c], start[c + 1] - start[c], threads);
    };
    std::size_t largest = 0;
    for (const std::uint32_t c : candidates) largest = std::max<std::size_t>(largest, segs_[c].voxels);
    const std::size_t budget = std::max(largest, labels_.size() / 256);
    const bool parallel = resolve_threads(p_.threads) > 1;
    for (std::size_t c0 = 0, c1; c0 < candidates.size(); c0 = c1) {
      std::size_t sum = segs_[candidates[c0]].voxels;
      for (c1 = c0 + 1; parallel && c1 < candidates.size() && sum + segs_[candidates[c1]].voxels <= budget; ++c1)
        sum += segs_[candidates[c1]].voxels;
      if (c1 == c0 + 1) {
        search_one(*this, c0, p_.threads);
        apply();
        continue;
      }
      std::vector<std::unique_ptr<Structure>> batch(c1 - c0);
      for (auto& e : batch) e = std::make_unique<Structure>(g_, labels_, segs_, p_, k_);
      // Largest first: the threads take them in that order, so a large one is not left for last
      // (the searches are independent; the splits below keep candidate order).
      std::vector<std::size_t> order(batch.size());
      std::iota(order.begin(), order.end(), std::size_t{0});
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return segs_[candidates[c0 + a]].voxels > segs_[candidates[c0 + b]].voxels;
      });
      parallel_for_dynamic(batch.size(), p_.threads, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) search_one(*batch[order[i]], c0 + order[i], 1);
      });
      for (auto& e : batch) {
        e->apply();
        pieces_.insert(pieces_.end(), e->pieces_.begin(), e->pieces_.end());
        wide_.insert(wide_.end(), e->wide_.begin(), e->wide_.end());
        e.reset();  // (its scratch back before the next split)
      }
    }
    attract_fragments();
    if (out)
      for (const Piece& pc : pieces_)
        out->push_back({pc.pl.n, pc.pl.d, pc.u, pc.v, pc.u0, pc.u1, pc.v0, pc.v1, pc.lo, pc.hi, pc.voxel});
  }

 private:
  static constexpr std::uint32_t kTop = std::numeric_limits<std::uint32_t>::max();

  static std::size_t box_volume(const Segment& s) {
    std::size_t v = 1;
    for (int k = 0; k < 3; ++k) v *= std::size_t(s.bbox_max[k] - s.bbox_min[k]) + 1;
    return v;
  }

  Vec coords(std::size_t i) const {
    return {double(i % d_.nx), double((i / d_.nx) % d_.ny), double(i / (d_.nx * d_.ny))};
  }

  // Whether a piece spans structure_extent along both of its own axes (structural if it is also
  // an area and flat; wide otherwise).
  bool spans_extent(const Piece& pc) const { return pc.u1 - pc.u0 + 1 >= extent_ && pc.v1 - pc.v0 + 1 >= extent_; }

  void list_members(std::uint32_t s, std::vector<std::uint32_t>& out) const {
    out.clear();
    const Segment& seg = segs_[s];
    // Room for exactly its voxels, the old storage freed first: grown by push_back, the list of a
    // noisy map's one sprawling segment peaked at its old and new storage together, 2.5 times
    // the list's size.
    if (out.capacity() < seg.voxels) {
      out = std::vector<std::uint32_t>();
      out.reserve(seg.voxels);
    }
    for (std::size_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
      for (std::size_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
        const std::size_t row = g_.index(0, y, z);
        for_label(row + seg.bbox_min[0], row + seg.bbox_max[0] + 1, s,
                  [&](std::size_t i) { out.push_back(static_cast<std::uint32_t>(i)); });
      }
  }

  // f(i) for the voxels i in [b, e) labelled s, in order; 16 voxels at a time are passed over
  // when none is (one vectorised test: a segment is sparse in its box).
  template <class F>
  void for_label(std::size_t b, std::size_t e, std::uint32_t s, F&& f) const {
    const std::uint32_t* l = labels_.data();
    std::size_t i = b;
    for (; i + 16 <= e; i += 16) {
      unsigned any = 0;
      for (int j = 0; j < 16; ++j) any |= unsigned(l[i + std::size_t(j)] == s);
      if (!any) continue;
      for (std::size_t j = i; j < i + 16; ++j)
        if (l[j] == s) f(j);
    }
    for (; i < e; ++i)
      if (l[i] == s) f(i);
  }

  // The neighbours of voxel i inside the map, in VoxelNeighbours' order.
  template <class F>
  void for_neighbours(std::size_t i, F&& f) const {
    neighbours_.for_each(i, f);
  }

  bool voxel_at(const Vec& c, double t, const Vec& n, std::size_t& out) const {
    const double q[3] = {std::round(c[0] + t * n[0]), std::round(c[1] + t * n[1]), std::round(c[2] + t * n[2])};
    const double lim[3] = {double(d_.nx), double(d_.ny), double(d_.nz)};
    for (int k = 0; k < 3; ++k)
      if (q[k] < 0 || q[k] >= lim[k]) return false;
    out = g_.index(std::size_t(q[0]), std::size_t(q[1]), std::size_t(q[2]));
    return true;
  }

  // The pieces of one plane's inliers (indices into members_): cells of cell_ x cell_ voxels in
  // the plane's (u, v) coordinates, 8-adjacent cells joined. Returns the piece of each inlier.
  // `inner` receives, per piece, its cells whose four in-plane neighbours are cells of it too: an
  // area (a floor, a wall) has many, a curve (the cross-section of a curved shell, a ring on a
  // cone) almost none.
  std::vector<std::uint32_t> plane_pieces(const std::vector<std::uint32_t>& inl, const Vec& u, const Vec& v,
                                          std::size_t& count, std::vector<std::size_t>& cells_of,
                                          std::vector<std::size_t>& inner) const {
    // A cell (a, b) is the key (a + 2^31) 2^32 + (b + 2^31): keys sort as the pairs do (the
    // coordinates are far inside 32 bits), and a neighbour's key is the cell's plus du 2^32 + dv.
    const auto key = [](std::int64_t a, std::int64_t b) {
      return (std::uint64_t(a + (std::int64_t(1) << 31)) << 32) | std::uint64_t(b + (std::int64_t(1) << 31));
    };
    const std::size_t N = inl.size();
    std::vector<std::int64_t> ca(N), cb(N);
    std::int64_t amin = std::numeric_limits<std::int64_t>::max(), amax = std::numeric_limits<std::int64_t>::min();
    std::int64_t bmin = amin, bmax = amax;
    for (std::size_t i = 0; i < N; ++i) {
      const Vec& q = pts_[inl[i]];
      ca[i] = static_cast<std::int64_t>(std::floor(dot(q, u) / cell_));
      cb[i] = static_cast<std::int64_t>(std::floor(dot(q, v) / cell_));
      amin = std::min(amin, ca[i]), amax = std::max(amax, ca[i]);
      bmin = std::min(bmin, cb[i]), bmax = std::max(bmax, cb[i]);
    }
    // The sorted distinct cells and each inlier's place among them (cell_at): when the cells' box
    // is small against the inliers, by marking a dense array over it in key order (row a, then b:
    // the keys' order), else by sorting the keys and a binary search per inlier.
    std::vector<std::uint64_t> cells;
    std::vector<std::uint32_t> cell_at(N);
    const std::uint64_t A = N ? std::uint64_t(amax - amin) + 1 : 0, B = N ? std::uint64_t(bmax - bmin) + 1 : 0;
    const std::uint64_t dense_max = std::max<std::uint64_t>(4096, 4 * std::uint64_t(N));
    if (N && A <= dense_max && B <= dense_max && A * B <= dense_max) {
      std::vector<std::uint32_t> dense(A * B, 0);
      for (std::size_t i = 0; i < N; ++i) dense[std::uint64_t(ca[i] - amin) * B + std::uint64_t(cb[i] - bmin)] = 1;
      for (std::uint64_t a = 0, at = 0; a < A; ++a)
        for (std::uint64_t b = 0; b < B; ++b, ++at)
          if (dense[at]) {
            dense[at] = static_cast<std::uint32_t>(cells.size());
            cells.push_back(key(amin + std::int64_t(a), bmin + std::int64_t(b)));
          }
      for (std::size_t i = 0; i < N; ++i)
        cell_at[i] = dense[std::uint64_t(ca[i] - amin) * B + std::uint64_t(cb[i] - bmin)];
    } else {
      std::vector<std::uint64_t> cell(N);
      for (std::size_t i = 0; i < N; ++i) cell[i] = key(ca[i], cb[i]);
      cells = cell;
      std::sort(cells.begin(), cells.end());
      cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
      for (std::size_t i = 0; i < N; ++i)
        cell_at[i] = static_cast<std::uint32_t>(std::lower_bound(cells.begin(), cells.end(), cell[i]) - cells.begin());
    }
    std::vector<std::uint32_t> parent(cells.size());
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&](std::uint32_t a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    const auto neighbour = [](std::uint64_t c, int du, int dv) {
      return c + (std::uint64_t(std::int64_t(du)) << 32) + std::uint64_t(std::int64_t(dv));
    };
    // Each pair of 8-adjacent cells once: (a, b + 1), then (a + 1, b + dv) for dv = -1, 0, 1. For
    // each dv the keys grow with c, so they are found by a pointer per dv that only moves forward
    // (ahead[dv + 1]: the first cell at or after the last such key), not by binary searches.
    const std::size_t C = cells.size();
    const auto join = [&](std::size_t c, std::size_t d) {
      std::uint32_t a = find(static_cast<std::uint32_t>(c)), b = find(static_cast<std::uint32_t>(d));
      if (a == b) return;
      if (a > b) std::swap(a, b);
      parent[b] = a;
    };
    std::size_t ahead[3] = {0, 0, 0};
    for (std::size_t c = 0; c < C; ++c) {
      if (c + 1 < C && cells[c + 1] == neighbour(cells[c], 0, 1)) join(c, c + 1);
      for (int dv = -1; dv <= 1; ++dv) {
        const std::uint64_t w = neighbour(cells[c], 1, dv);
        std::size_t& at = ahead[dv + 1];
        while (at < C && cells[at] < w) ++at;
        if (at < C && cells[at] == w) join(c, at);
      }
    }
    // Pieces numbered by their first cell.
    std::vector<std::uint32_t> number(cells.size(), ~0u);
    count = 0;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::uint32_t r = find(static_cast<std::uint32_t>(c));
      if (number[r] == ~0u) number[r] = static_cast<std::uint32_t>(count++);
    }
    cells_of.assign(count, 0);
    inner.assign(count, 0);
    // A cell is inner when its four in-plane neighbours are cells: (a, b -+ 1) are the cells beside
    // it in the sorted list, (a -+ 1, b) found by forward-only pointers as above.
    std::size_t behind = 0, after = 0;
    for (std::size_t c = 0; c < C; ++c) {
      const std::uint32_t k = number[find(static_cast<std::uint32_t>(c))];
      ++cells_of[k];
      const std::uint64_t w = cells[c], wm = neighbour(w, -1, 0), wp = neighbour(w, 1, 0);
      while (behind < C && cells[behind] < wm) ++behind;
      while (after < C && cells[after] < wp) ++after;
      inner[k] += behind < C && cells[behind] == wm && after < C && cells[after] == wp && c > 0 &&
                  cells[c - 1] == neighbour(w, 0, -1) && c + 1 < C && cells[c + 1] == neighbour(w, 0, 1);
    }
    std::vector<std::uint32_t> piece(N);
    for (std::size_t i = 0; i < N; ++i) piece[i] = number[find(cell_at[i])];
    return piece;
  }

  // The thickness of segment s along axis `axis` through voxel centre c: the voxels from the last
  // voxel of s reached stepping in -axis to the last one in +axis, crossing gaps of at most
  // object_gap voxels not in s (the unknown between rings of returns); counted up to `cap`.
  int thickness(std::uint32_t s, const Vec& c, int axis, int cap) const {
    const std::size_t lim[3] = {d_.nx, d_.ny, d_.nz};
    const long stride[3] = {1, long(d_.nx), long(d_.nx * d_.ny)};
    const long at = long(c[std::size_t(axis)]);
    const std::size_t i0 = g_.index(std::size_t(c[0]), std::size_t(c[1]), std::size_t(c[2]));
    int run = 1;
    for (int dir = -1; dir <= 1; dir += 2) {
      int gap = 0;
      const long room = dir < 0 ? at : long(lim[axis]) - 1 - at;  // steps before the map's face
      const long step = dir * stride[axis];
      long j = long(i0);
      for (long t = 1; run < cap && t <= room; ++t) {
        j += step;
        if (labels_[std::size_t(j)] == s) {
          run += gap + 1;
          gap = 0;
        } else if (++gap > p_.object_gap) {
          break;
        }
      }
    }
    return std::min(run, cap);
  }

  // axes[m] for every member m: bit a set when thickness(s, pts_[m], a, thin + 1) <= thin (thin:
  // max(4, object_gap + 2)), 64 voxels of a row at a time on a bit mask of s over its box.
  void thin_axes(std::uint32_t s, std::vector<std::uint8_t>& axes) const {
    switch (p_.object_gap) {
#define OCCSEG_THIN_AXES(G) \
  case G:                   \
    return thin_axes<G>(s, axes);
      OCCSEG_THIN_AXES(0) OCCSEG_THIN_AXES(1) OCCSEG_THIN_AXES(2) OCCSEG_THIN_AXES(3) OCCSEG_THIN_AXES(4)
      OCCSEG_THIN_AXES(5) OCCSEG_THIN_AXES(6) OCCSEG_THIN_AXES(7) OCCSEG_THIN_AXES(8) OCCSEG_THIN_AXES(9)
      OCCSEG_THIN_AXES(10) OCCSEG_THIN_AXES(11) OCCSEG_THIN_AXES(12) OCCSEG_THIN_AXES(13) OCCSEG_THIN_AXES(14)
      OCCSEG_THIN_AXES(15) OCCSEG_THIN_AXES(16)
#undef OCCSEG_THIN_AXES
      default:  // (beyond the parameter's range)
        break;
    }
    const int thin = std::max(4, p_.object_gap + 2);
    for (std::size_t m = 0; m < members_.size(); ++m)
      for (int a = 0; a < 3; ++a)
        if (thickness(s, pts_[m], a, thin + 1) <= thin) axes[m] |= std::uint8_t(1u << a);
  }

  // Along one direction, with B_j the bits of the voxels j steps on (1 <= j <= thin + G): the walk
  // of thickness() reaches j steps or more (R_j) exactly when no G + 1 consecutive steps in
  // 1 .. j + G miss s (a voxel of s among steps j .. j + G is then reached, each gap crossed being
  // at most G), so R_j = E_1 & ... & E_j with E_t = B_t | ... | B_(t+G). The probe counts
  // 1 + reach(-) + reach(+), capped at thin + 1: the voxel is thick when R+_P & R-_(thin-P) for
  // some P in 0 .. thin (R_0: all).
  template <int G>
  void thin_axes(std::uint32_t s, std::vector<std::uint8_t>& axes) const {
    constexpr int T = std::max(4, G + 2), L = T + G;  // thin, and the steps a direction needs
    static_assert(L < 64, "a row's shifts stay within one word");
    using W = std::uint64_t;
    const std::size_t n = members_.size();
    const Segment& seg = segs_[s];
    const std::size_t x0 = seg.bbox_min[0], y0 = seg.bbox_min[1], z0 = seg.bbox_min[2];
    const std::size_t bx = seg.bbox_max[0] - x0 + 1, by = seg.bbox_max[1] - y0 + 1, bz = seg.bbox_max[2] - z0 + 1;
    const std::size_t wpr = (bx + 63) / 64, layer = by * wpr;  // words per row, per layer
    std::vector<W> vol(layer * bz, 0);
    for (std::size_t m = 0; m < n; ++m) {
      const std::size_t i = members_[m];
      const std::size_t x = i % d_.nx - x0, y = (i / d_.nx) % d_.ny - y0, z = i / (d_.nx * d_.ny) - z0;
      vol[z * layer + y * wpr + x / 64] |= W(1) << (x % 64);
    }
    const auto reach = [](const W* b, W* r) {  // b[1 .. L] -> r[1 .. T]
      W all = ~W(0);
      for (int t = 1; t <= T; ++t) {
        W e = 0;
        for (int i = t; i <= t + G; ++i) e |= b[i];
        r[t] = all &= e;
      }
    };
    const auto thick = [&](const W* bp, const W* bm) {
      W rp[T + 1], rm[T + 1];
      reach(bp, rp);
      reach(bm, rm);
      W t = rp[T] | rm[T];
      for (int q = 1; q < T; ++q) t |= rp[q] & rm[T - q];
      return t;
    };
    W bp[L + 1], bm[L + 1];
    std::size_t m = 0;
    for (std::size_t z = 0; z < bz; ++z)
      for (std::size_t y = 0; y < by; ++y) {
        const W* row = vol.data() + z * layer + y * wpr;
        for (std::size_t w = 0; w < wpr; ++w) {
          const W own = row[w];
          if (!own) continue;
          W thin_of[3];
          {  // x: the row's bits shifted, across its words
            const W next = w + 1 < wpr ? row[w + 1] : 0, prev = w > 0 ? row[w - 1] : 0;
            for (int k = 1; k <= L; ++k)
              bp[k] = (own >> k) | (next << (64 - k)), bm[k] = (own << k) | (prev >> (64 - k));
            thin_of[0] = ~thick(bp, bm);
          }
          // y: the rows beside it in its layer; z: the rows above and below it
          const std::size_t at[2] = {y, z}, lim[2] = {by, bz}, stride[2] = {wpr, layer};
          for (int a = 0; a < 2; ++a) {
            for (int k = 1; k <= L; ++k) {
              const std::size_t o = std::size_t(k) * stride[a];
              bp[k] = at[a] + std::size_t(k) < lim[a] ? row[o + w] : 0;
              bm[k] = at[a] >= std::size_t(k) ? *(row - o + w) : 0;
            }
            thin_of[1 + a] = ~thick(bp, bm);
          }
          for (W bits = own; bits; bits &= bits - 1) {  // the members in scan order
            const int b = __builtin_ctzll(bits);
            axes[m++] = std::uint8_t((thin_of[0] >> b & 1) | (thin_of[1] >> b & 1) << 1 | (thin_of[2] >> b & 1) << 2);
          }
        }
      }
  }

  // A box around the points within distance t of a piece's plane over its extent widened by w
  // (a <= u . x - u0 ... ): wider than that by a voxel edge, so rounding never leaves out a point
  // the exact tests would take. at(i0 .. i1): the voxels of the segment (indices into pts_) in its
  // range along the axis that has the fewest there, in order along it (pts_ is in scan order, so
  // by z; by_ holds the orders by x and by y). Its users' results do not depend on the order.
  struct Box {
    double lo[3], hi[3];
    const std::uint32_t* order = nullptr;  // nullptr: scan order
    std::size_t i0 = 0, i1 = 0;
    // rows: visit the rows (y, z) of the box instead (rows_), each over its x range only.
    bool rows = false;
    long x0 = 0, x1 = -1, y0 = 0, y1 = -1, z0 = 0, z1 = -1;
    std::size_t at(std::size_t i) const { return order ? order[i] : i; }
    bool holds(const Vec& q) const {
      return q[0] >= lo[0] && q[0] <= hi[0] && q[1] >= lo[1] && q[1] <= hi[1] && q[2] >= lo[2] && q[2] <= hi[2];
    }
  };
  Box band_box(const Piece& pc, double t, double w) const {
    Box b;
    const double ca = 0.5 * (pc.u0 + pc.u1), ha = 0.5 * (pc.u1 - pc.u0) + w;
    const double cb = 0.5 * (pc.v0 + pc.v1), hb = 0.5 * (pc.v1 - pc.v0) + w;
    for (int k = 0; k < 3; ++k) {
      // (u, v, n orthonormal: a point is a u + b v + (d + e) n)
      const double c = ca * pc.u[k] + cb * pc.v[k] + pc.pl.d * pc.pl.n[k];
      const double h = ha * std::fabs(pc.u[k]) + hb * std::fabs(pc.v[k]) + t * std::fabs(pc.pl.n[k]) + 1.0;
      b.lo[k] = c - h, b.hi[k] = c + h;
    }
    std::size_t best = ~std::size_t(0);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t* order = k < 2 ? by_[k].data() : nullptr;
      const auto key = [&](std::size_t i) { return pts_[order ? order[i] : i][std::size_t(k)]; };
      std::size_t lo = 0, hi = pts_.size();  // first i with key >= b.lo[k]
      while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (key(mid) < b.lo[k]) lo = mid + 1; else hi = mid;
      }
      const std::size_t i0 = lo;
      hi = pts_.size();  // first i with key > b.hi[k]
      while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (key(mid) <= b.hi[k]) lo = mid + 1; else hi = mid;
      }
      if (lo - i0 < best) best = lo - i0, b.order = order, b.i0 = i0, b.i1 = lo;
    }
    // The box's integer coordinates (the voxels holds() takes), rows clamped to rows_' box; its
    // rows are walked when they are few against the voxels of the range above.
    b.x0 = long(std::ceil(b.lo[0])), b.x1 = long(std::floor(b.hi[0]));
    b.y0 = std::max(long(std::ceil(b.lo[1])), row_y0_), b.y1 = std::min(long(std::floor(b.hi[1])), row_y0_ + row_by_ - 1);
    b.z0 = std::max(long(std::ceil(b.lo[2])), row_z0_), b.z1 = std::min(long(std::floor(b.hi[2])), row_z0_ + row_bz_ - 1);
    const std::size_t rows = b.y0 <= b.y1 && b.z0 <= b.z1 ? std::size_t(b.y1 - b.y0 + 1) * std::size_t(b.z1 - b.z0 + 1) : 0;
    b.rows = 4 * rows < best;
    return b;
  }

  // f(m) for the voxels of the box's range (Box::at), or of its rows; the order differs, the set
  // of voxels holds() takes does not.
  template <class F>
  void for_box(const Box& b, F&& f) const {
    if (!b.rows) {
      for (std::size_t i = b.i0; i < b.i1; ++i) f(b.at(i));
      return;
    }
    const double x0 = double(b.x0), x1 = double(b.x1);
    for (long z = b.z0; z <= b.z1; ++z)
      for (long y = b.y0; y <= b.y1; ++y) {
        const std::size_t r = std::size_t(z - row_z0_) * std::size_t(row_by_) + std::size_t(y - row_y0_);
        std::size_t lo = rows_[r], hi = rows_[r + 1];
        while (lo < hi) {  // first voxel of the row with x >= x0
          const std::size_t mid = lo + (hi - lo) / 2;
          if (pts_[mid][0] < x0) lo = mid + 1; else hi = mid;
        }
        for (std::size_t m = lo, e = rows_[r + 1]; m < e && pts_[m][0] <= x1; ++m) f(m);
      }
  }

  // Robust spread of a plane's surface: 1.4826 x the median |distance| of the segment's voxels
  // within 4 voxel edges of it and over the piece's extent (as rules/planes.cpp) that can be the
  // surface's own voxels or its noise: thin along the piece's axis (`axes`, examine()) and of no
  // other structural piece (`piece_of`; this one is `self`). What meets or stands on the surface
  // within the band (the feet of a building's walls and furniture on its floor, the floor and
  // ceiling along a wall's foot and head) is thick along that axis, and another structural piece
  // parallel within the band (the floor under a layer of its noise found as a piece of its own)
  // is another surface: counted, they inflate the spread and so the height an object must rise
  // (split()).
  double surface_sigma(const Piece& pc, std::int32_t self, const std::vector<std::uint8_t>& axes,
                       const std::vector<std::int32_t>& piece_of) const {
    std::vector<double> near;
    const Box box = band_box(pc, 4.0, 0.0);
    for_box(box, [&](std::size_t m) {
      const Vec& q = pts_[m];
      if (!box.holds(q) || !(axes[m] >> pc.axis & 1) || (piece_of[m] >= 0 && piece_of[m] != self)) return;
      const double e = std::fabs(pc.pl.distance(q[0], q[1], q[2]));
      if (e > 4.0) return;
      const double a = dot(q, pc.u), b = dot(q, pc.v);
      if (a < pc.u0 || a > pc.u1 || b < pc.v0 || b > pc.v1) return;
      near.push_back(e);
    });
    if (near.empty()) return 0;
    std::nth_element(near.begin(), near.begin() + std::ptrdiff_t(near.size() / 2), near.end());
    return 1.4826 * near[near.size() / 2];
  }

  // Whether voxel c of segment s is thin along some axis (a surface voxel; examine()).
  bool thin_somewhere(std::uint32_t s, const Vec& c) const {
    const int thin = std::max(4, p_.object_gap + 2);
    for (int a = 0; a < 3; ++a)
      if (thickness(s, c, a, thin + 1) <= thin) return true;
    return false;
  }

  // examine()'s sample test on the same voxels (the members in scan order of the box, every
  // n / k-th), found by scanning the box instead of reading a list: its rows counted on `threads`
  // threads first (the region of noise this test rejects fills a third of its box), then only the
  // rows holding a sample walked.
  bool has_surfaces_in_box(std::uint32_t s, int threads) const {
    const Segment& seg = segs_[s];
    const std::size_t n = seg.voxels, k = std::min<std::size_t>(n, 4096);
    const std::vector<std::uint32_t> counts = box_row_members(d_, labels_.data(), seg, s, threads, k_.planes);
    const std::size_t rows_y = std::size_t(seg.bbox_max[1] - seg.bbox_min[1]) + 1;
    std::size_t seen = 0, next = 0, i = 0, surface = 0;
    for (std::size_t r = 0; r < counts.size() && i < k; ++r) {
      if (seen + counts[r] <= next) {
        seen += counts[r];
        continue;
      }
      const std::size_t row = g_.index(0, seg.bbox_min[1] + r % rows_y, seg.bbox_min[2] + r / rows_y);
      for_label(row + seg.bbox_min[0], row + seg.bbox_max[0] + 1, s, [&](std::size_t j) {
        if (i >= k || seen++ != next) return;  // (the row's members past the last sample: none)
        surface += thin_somewhere(s, coords(j));
        next = ++i * n / k;
      });
    }
    return 100 * surface >= kMinSurfacePercent * k;
  }

  // Phase one of examining candidate s (reads only; apply() is phase two): its voxels are
  // [bucket, bucket + count) when the caller bucketed them, else (bucket = nullptr) found by
  // scanning its box after the sample test there.
  void search(std::uint32_t s, const std::uint32_t* bucket, std::size_t count, int threads) {
    s_ = s;
    found_ = false;
    if (!bucket) {
      // The sample test first, by a scan of the box: a sprawling region of noise is rejected
      // before its voxels are listed (a list of 4 bytes per voxel of most of a noisy map).
      if (!has_surfaces_in_box(s, threads)) return;
      list_members(s, listed_);
      members_ = {listed_.data(), listed_.size()};
    } else {
      members_ = {bucket, count};
    }
    examine(s, bucket != nullptr);
  }

  // Phase two: a segment with a structural piece is split; the pieces of one without still
  // gather coplanar fragments.
  void apply() {
    if (!found_) return;
    found_ = false;
    if (!std::any_of(local_.begin(), local_.end(), [](const Piece& pc) { return pc.structural; })) {
      pieces_.insert(pieces_.end(), local_.begin(), local_.end());
      return;
    }
    segs_[s_].kind = Kind::structure;
    split(s_, local_, piece_of_, axes_);
  }

  // The plane searches over segment s's voxels (members_); `sample`: whether the sample test is
  // still to be made (has_surfaces_in_box() made it on the same voxels otherwise).
  void examine(std::uint32_t s, bool sample) {
    const std::size_t n = members_.size();
    // Each voxel's possible orientations: axis a when the segment is thin along a through it
    // (thickness() at most max(4, object_gap + 2) voxels: a floor along z, a wall along its
    // normal). A horizontal ring of returns on a wall is thick along z (the rings above and below
    // it) and is never searched as a horizontal plane; a floor's voxels are.
    // The planes are searched among the voxels of one orientation at a time (z: floors, ceilings,
    // table tops first; then y, then x): a plane within 45 degrees of an axis is found among that
    // axis' voxels.
    // A segment whose voxels are mostly thick along every axis (a sprawling region of noise) holds
    // no surfaces: judged on an evenly strided sample of at most 4096 of its voxels before any
    // work per voxel.
    if (sample) {
      const std::size_t k = std::min<std::size_t>(n, 4096);
      std::size_t surface = 0;
      for (std::size_t i = 0; i < k; ++i) surface += thin_somewhere(s, coords(members_[i * n / k]));
      if (100 * surface < kMinSurfacePercent * k) return;
    }
    // Past the sample only: a segment skipped above never costs memory per voxel.
    pts_.resize(n);
    for (std::size_t m = 0; m < n; ++m) pts_[m] = coords(members_[m]);
    {  // by_: the voxels in order of x, and of y (counting sorts, ties in scan order)
      const std::size_t dims[2] = {d_.nx, d_.ny};
      std::vector<std::size_t> start;
      for (int k = 0; k < 2; ++k) {
        start.assign(dims[k] + 1, 0);
        for (std::size_t m = 0; m < n; ++m) ++start[std::size_t(pts_[m][std::size_t(k)]) + 1];
        for (std::size_t c = 1; c <= dims[k]; ++c) start[c] += start[c - 1];
        by_[k].resize(n);
        for (std::size_t m = 0; m < n; ++m) by_[k][start[std::size_t(pts_[m][std::size_t(k)])]++] = std::uint32_t(m);
      }
    }
    {  // rows_: where each row (y, z) of the voxels' box starts in pts_ (scan order)
      long y0 = long(d_.ny), y1 = 0, z0 = long(d_.nz), z1 = 0;
      for (std::size_t m = 0; m < n; ++m) {
        const long y = long(pts_[m][1]), z = long(pts_[m][2]);
        y0 = std::min(y0, y), y1 = std::max(y1, y), z0 = std::min(z0, z), z1 = std::max(z1, z);
      }
      row_y0_ = y0, row_z0_ = z0, row_by_ = y1 - y0 + 1, row_bz_ = z1 - z0 + 1;
      rows_.assign(std::size_t(row_by_) * std::size_t(row_bz_) + 1, 0);
      for (std::size_t m = 0; m < n; ++m)
        ++rows_[std::size_t(long(pts_[m][2]) - z0) * std::size_t(row_by_) + std::size_t(long(pts_[m][1]) - y0) + 1];
      for (std::size_t r = 1; r < rows_.size(); ++r) rows_[r] += rows_[r - 1];
    }
    std::vector<std::int32_t>& piece_of = piece_of_;  // structural piece (index into local) or -1
    std::vector<Piece>& local = local_;               // this segment's pieces of >= min_plane voxels
    std::vector<std::uint8_t>& axes = axes_;
    piece_of.assign(n, -1);
    local.clear();
    axes.assign(n, 0);
    thin_axes(s, axes);
    // The rest: the voxels of the axis no plane holds yet (indices into pts_), and their
    // coordinates by axis (rx, ry, rz) for the fits, kept in step (compacted after each plane).
    std::vector<std::uint32_t> rest;
    std::vector<double> rx, ry, rz;
    std::vector<std::uint32_t> inl, positions;
    for (int axis = 2, it = 0; axis >= 0; --axis) {
      rest.clear();
      for (std::size_t m = 0; m < n; ++m)
        if ((axes[m] >> axis & 1) && piece_of[m] < 0) rest.push_back(static_cast<std::uint32_t>(m));
      rx.resize(rest.size()), ry.resize(rest.size()), rz.resize(rest.size());
      for (std::size_t r = 0; r < rest.size(); ++r)
        rx[r] = pts_[rest[r]][0], ry[r] = pts_[rest[r]][1], rz[r] = pts_[rest[r]][2];
      for (int tries = 0; tries < p_.structure_planes && rest.size() >= min_plane_; ++tries, ++it) {
      Plane pl;
      std::size_t count = 0;
      const std::uint64_t seed = 0x737472756374ull ^ (std::uint64_t(members_[0]) * 0x9E3779B97F4A7C15ull) ^
                                 (std::uint64_t(it) * 0xD1B54A32D192ED03ull);
      const kernels::PlanePoints rp{rx.data(), ry.data(), rz.data(), rest.size()};
      if (!fit_dominant_plane(rp, seed, pl, count, 1, k_, axis, &positions) || count < min_plane_) break;
      if (std::fabs(pl.n[std::size_t(axis)]) < std::sqrt(0.5)) break;  // (refitted away from the axis)
      // The plane's inliers among the rest (the fit's, in order), and what stays: compacted in
      // place, the stretches between runs of inliers moved at once.
      inl.clear();
      std::size_t kept = 0, from = 0;  // rest[from ..) not yet placed
      const auto move = [&](std::size_t b, std::size_t e) {
        if (kept != b && e - b < 16) {  // (short stretches: cheaper than four calls of memmove)
          for (std::size_t r = b; r < e; ++r) {
            const std::size_t t = kept + (r - b);
            rest[t] = rest[r], rx[t] = rx[r], ry[t] = ry[r], rz[t] = rz[r];
          }
        } else if (kept != b) {
          std::copy(rest.data() + b, rest.data() + e, rest.data() + kept);
          std::copy(rx.data() + b, rx.data() + e, rx.data() + kept);
          std::copy(ry.data() + b, ry.data() + e, ry.data() + kept);
          std::copy(rz.data() + b, rz.data() + e, rz.data() + kept);
        }
        kept += e - b;
      };
      for (std::size_t i = 0; i < positions.size();) {
        const std::size_t p = positions[i];
        std::size_t q = p;  // the run p .. q - 1 of inliers
        for (; i < positions.size() && positions[i] == q; ++i, ++q) inl.push_back(rest[q]);
        move(from, p);
        from = q;
      }
      move(from, rest.size());
      rest.resize(kept);
      Vec u, v;
      plane_basis(pl.n, u, v);
      std::size_t pieces = 0;
      std::vector<std::size_t> cells_of, inner;
      const std::vector<std::uint32_t> piece = plane_pieces(inl, u, v, pieces, cells_of, inner);
      // Each piece's extent along its own principal axes in the plane (a diagonal strip is narrow,
      // whatever the plane's basis).
      std::vector<Piece> found(pieces);
      std::vector<std::array<double, 5>> mom(pieces, {0, 0, 0, 0, 0});  // sums of a, b, aa, ab, bb
      for (std::size_t i = 0; i < inl.size(); ++i) {
        Piece& pc = found[piece[i]];
        const Vec& q = pts_[inl[i]];
        const double a = dot(q, u), b = dot(q, v);
        std::array<double, 5>& m = mom[piece[i]];
        m[0] += a, m[1] += b, m[2] += a * a, m[3] += a * b, m[4] += b * b;
        if (pc.voxels == 0) {
          pc.lo = pc.hi = {std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2])};
          pc.voxel = members_[inl[i]];
        }
        for (int k = 0; k < 3; ++k)
          pc.lo[k] = std::min(pc.lo[k], std::uint32_t(q[k])), pc.hi[k] = std::max(pc.hi[k], std::uint32_t(q[k]));
        ++pc.voxels;
      }
      for (std::size_t q = 0; q < pieces; ++q) {
        Piece& pc = found[q];
        const std::array<double, 5>& m = mom[q];
        const double k = double(pc.voxels), ma = m[0] / k, mb = m[1] / k;
        const double caa = m[2] / k - ma * ma, cab = m[3] / k - ma * mb, cbb = m[4] / k - mb * mb;
        const double th = 0.5 * std::atan2(2 * cab, caa - cbb), c = std::cos(th), sn = std::sin(th);
        for (int j = 0; j < 3; ++j) pc.u[j] = c * u[j] + sn * v[j], pc.v[j] = -sn * u[j] + c * v[j];
        pc.u0 = pc.v0 = std::numeric_limits<double>::infinity();
        pc.u1 = pc.v1 = -pc.u0;
      }
      for (std::size_t i = 0; i < inl.size(); ++i) {
        Piece& pc = found[piece[i]];
        const Vec& q = pts_[inl[i]];
        const double a = dot(q, pc.u), b = dot(q, pc.v);
        pc.u0 = std::min(pc.u0, a), pc.u1 = std::max(pc.u1, a), pc.v0 = std::min(pc.v0, b), pc.v1 = std::max(pc.v1, b);
      }
      std::vector<char> curved(pieces, 0);
      std::vector<std::int32_t> index(pieces, -1);
      for (std::size_t q = 0; q < pieces; ++q) {
        Piece& pc = found[q];
        if (pc.voxels < min_plane_) continue;
        pc.segment = s, pc.pl = pl, pc.axis = axis;
        // Structural: wide both ways, an area (at least a quarter of its cells inner ones), and flat.
        pc.structural = spans_extent(pc) && 4 * inner[q] >= cells_of[q];
        if (pc.structural) curved[q] = 1;  // decided below
        index[q] = static_cast<std::int32_t>(local.size());
        local.push_back(pc);
      }
      // Flatness: the least-squares fit d = c0 + c1 a^2 + c2 b^2 of the signed distances over each
      // candidate piece (a, b centred on its principal axes) sags by under kMaxSag voxel edges
      // across it. A gently curved shell (a cone's side under range noise) lies within the
      // inlier band over a wide patch, but its centre and its edges sit on opposite sides.
      std::vector<std::array<double, 9>> ls(pieces);  // sums: 1, A, B, AA, AB, BB, d, dA, dB
      for (std::size_t q = 0; q < pieces; ++q) ls[q].fill(0);
      for (std::size_t i = 0; i < inl.size(); ++i) {
        const std::size_t q = piece[i];
        if (!curved[q]) continue;
        const Piece& pc = found[q];
        const Vec& x = pts_[inl[i]];
        const double a = dot(x, pc.u) - 0.5 * (pc.u0 + pc.u1), b = dot(x, pc.v) - 0.5 * (pc.v0 + pc.v1);
        const double A = a * a, B = b * b, e = pl.distance(x[0], x[1], x[2]);
        std::array<double, 9>& t = ls[q];
        t[0] += 1, t[1] += A, t[2] += B, t[3] += A * A, t[4] += A * B, t[5] += B * B, t[6] += e, t[7] += e * A,
            t[8] += e * B;
      }
      for (std::size_t q = 0; q < pieces; ++q) {
        if (!curved[q]) continue;
        const std::array<double, 9>& t = ls[q];
        const double m[3][3] = {{t[0], t[1], t[2]}, {t[1], t[3], t[4]}, {t[2], t[4], t[5]}};
        const double r[3] = {t[6], t[7], t[8]};
        const auto det3 = [](const double a[3][3]) {
          return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                 a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        };
        const double det = det3(m);
        double c[3] = {0, 0, 0};
        if (std::fabs(det) > 0)
          for (int j = 0; j < 3; ++j) {
            double mj[3][3];
            for (int r0 = 0; r0 < 3; ++r0)
              for (int c0 = 0; c0 < 3; ++c0) mj[r0][c0] = c0 == j ? r[r0] : m[r0][c0];
            c[j] = det3(mj) / det;
          }
        const double hu = 0.5 * (found[q].u1 - found[q].u0), hv = 0.5 * (found[q].v1 - found[q].v0);
        const double sag = std::max(std::fabs(c[1]) * hu * hu, std::fabs(c[2]) * hv * hv);
        if (index[q] >= 0) local[std::size_t(index[q])].structural = sag < kMaxSag;
      }
      for (std::size_t i = 0; i < inl.size(); ++i) {
        const std::int32_t q = index[piece[i]];
        if (q >= 0 && local[std::size_t(q)].structural) piece_of[inl[i]] = q;
      }
      }
    }
    // Voxels the plane searches left out (those of no orientation: where a wall meets the floor,
    // under a box standing on it; a cross-section's) that lie on a structural piece's plane, over
    // its extent widened by a cell, belong to it.
    // (A voxel takes the first piece that holds it: the pieces in order, each over the voxels of
    // its band's box only, unclaimed ones.)
    const double w = cell_;
    for (std::size_t p = 0; p < local.size(); ++p) {
      const Piece& pc = local[p];
      if (!pc.structural) continue;
      const Box box = band_box(pc, kPlaneInlierDistance, w);
      for_box(box, [&](std::size_t m) {
        if (piece_of[m] >= 0) return;
        const Vec& q = pts_[m];
        if (!box.holds(q) || std::fabs(pc.pl.distance(q[0], q[1], q[2])) > kPlaneInlierDistance) return;
        const double a = dot(q, pc.u), b = dot(q, pc.v);
        if (a < pc.u0 - w || a > pc.u1 + w || b < pc.v0 - w || b > pc.v1 + w) return;
        piece_of[m] = static_cast<std::int32_t>(p);
      });
    }
    found_ = true;
  }

  // The noise of a structural surface is structure: a voxel still of s (no piece's) within half
  // the height an object must rise from a structural piece's plane, over its extent widened by a
  // cell, whose run of voxels still of s along the piece's axis (thickness(), crossing gaps of at
  // most object_gap) fits in that band, takes the piece's temporary label (the first such piece
  // in order; all decided before any is taken). Under range noise a building's floor has a layer
  // of voxels just above its inliers, which would otherwise join the feet of the furniture
  // standing on it to each other and to the walls; what stands on the floor (a leg, a box's side)
  // runs on above the band and stays.
  // (The pieces on the threads: a voxel takes the smallest piece index that claims it, by an
  // atomic minimum, so the order the pieces are looked at in changes nothing; a voxel an earlier
  // piece has taken already is passed over.)
  void claim_noise(std::uint32_t s, const std::vector<Piece>& local) {
    const std::size_t n = members_.size();
    constexpr std::uint32_t kNo = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> take(n, kNo);
    const double w = cell_;
    parallel_for_dynamic(local.size(), p_.threads, [&](std::size_t q0, std::size_t q1) {
      for (std::size_t q = q0; q < q1; ++q) {
        const Piece& pc = local[q];
        if (!pc.structural) continue;
        const double t = 0.5 * pc.min_height;
        const int fits = static_cast<int>(std::floor(2 * t));
        const Box box = band_box(pc, t, w);
        const auto qq = static_cast<std::uint32_t>(q);
        for_box(box, [&](std::size_t m) {
          std::uint32_t held = __atomic_load_n(&take[m], __ATOMIC_RELAXED);
          if (held < qq || labels_[members_[m]] != s) return;
          const Vec& x = pts_[m];
          if (!box.holds(x) || std::fabs(pc.pl.distance(x[0], x[1], x[2])) > t) return;
          const double a = dot(x, pc.u), b = dot(x, pc.v);
          if (a < pc.u0 - w || a > pc.u1 + w || b < pc.v0 - w || b > pc.v1 + w) return;
          if (thickness(s, x, pc.axis, fits + 1) > fits) return;
          while (held > qq && !__atomic_compare_exchange_n(&take[m], &held, qq, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
          }
        });
      }
    });
    for (std::size_t m = 0; m < n; ++m)
      if (take[m] != kNo) labels_[members_[m]] = kTop - take[m];
  }

  // Temporary labels, above every id: structural pieces kTop - q, remainder components below them.
  void split(std::uint32_t s, std::vector<Piece>& local, const std::vector<std::int32_t>& piece_of,
             const std::vector<std::uint8_t>& axes) {
    const std::size_t n = members_.size(), P = local.size();
    for (std::size_t m = 0; m < n; ++m)
      if (piece_of[m] >= 0) labels_[members_[m]] = kTop - static_cast<std::uint32_t>(piece_of[m]);
    const std::uint32_t first_temp = static_cast<std::uint32_t>(segs_.size());  // temporaries are above
    const auto member = [&](std::uint32_t l) { return l == s || l >= first_temp; };
    // (Each piece's spread, then its noise, on the threads: they only read the labels and the
    // voxels' lists.)
    parallel_for_dynamic(P, p_.threads, [&](std::size_t q0, std::size_t q1) {
      for (std::size_t q = q0; q < q1; ++q) {
        Piece& pc = local[q];
        if (!pc.structural) continue;
        pc.min_height = std::max(kMinObjectHeight, kNoiseHeights * surface_sigma(pc, std::int32_t(q), axes, piece_of));
      }
    });
    claim_noise(s, local);
    // Open sides: from each structural voxel, one to three voxels along +n and -n, the first voxel
    // outside the segment; a side is open when it saw free space at least a quarter as often as
    // the other (a wall between two rooms is open on both).
    // The voxel t steps along +-n from voxel centre c is round(c + t n) per coordinate; with c an
    // integer below 2^21 the sum is off by under 1e-9, so when t n is more than 1e-6 from a
    // half-integer in every coordinate it is c + round(t n): one offset per piece and step
    // (`shift`), else voxel_at() itself.
    struct Shift {
      bool exact = false;
      long o[3] = {0, 0, 0};
    };
    std::vector<std::array<Shift, 6>> shift(P);  // [side * 3 + step - 1]
    const bool small = d_.nx < (1u << 21) && d_.ny < (1u << 21) && d_.nz < (1u << 21);
    for (std::size_t q = 0; q < P && small; ++q)
      for (int side = 0; side < 2; ++side)
        for (int step = 1; step <= 3; ++step) {
          Shift& sh = shift[q][std::size_t(side * 3 + step - 1)];
          sh.exact = true;
          for (int k = 0; k < 3; ++k) {
            const double x = (side == 0 ? 1.0 : -1.0) * step * local[q].pl.n[std::size_t(k)];
            sh.o[k] = long(std::round(x));
            if (std::fabs(std::fabs(x - std::trunc(x)) - 0.5) <= 1e-6) sh.exact = false;
          }
        }
    const long lim[3] = {long(d_.nx), long(d_.ny), long(d_.nz)};
    const auto probe = [&](std::size_t m, const Shift& sh, double t, const Vec& nrm, std::size_t& w) {
      if (!sh.exact) return voxel_at(pts_[m], t, nrm, w);
      long q[3];
      for (int k = 0; k < 3; ++k) {
        q[k] = long(pts_[m][std::size_t(k)]) + sh.o[k];
        if (q[k] < 0 || q[k] >= lim[k]) return false;
      }
      w = g_.index(std::size_t(q[0]), std::size_t(q[1]), std::size_t(q[2]));
      return true;
    };
    std::vector<std::array<std::size_t, 2>> seen(P, {0, 0});
    for (std::size_t m = 0; m < n; ++m) {
      if (piece_of[m] < 0) continue;
      const Piece& pc = local[std::size_t(piece_of[m])];
      for (int side = 0; side < 2; ++side)
        for (int step = 1; step <= 3; ++step) {
          std::size_t w;
          const Shift& sh = shift[std::size_t(piece_of[m])][std::size_t(side * 3 + step - 1)];
          if (!probe(m, sh, (side == 0 ? 1.0 : -1.0) * step, pc.pl.n, w)) break;
          if (member(labels_[w])) continue;
          seen[std::size_t(piece_of[m])][std::size_t(side)] += segs_[labels_[w]].state == State::free;
          break;
        }
    }
    for (std::size_t q = 0; q < P; ++q)
      for (int side = 0; side < 2; ++side)
        local[q].open[side] = seen[q][side] > 0 && 4 * seen[q][side] >= seen[q][1 - side];
    // The components of the rest, in order of first voxel.
    const std::uint32_t comp_top = kTop - static_cast<std::uint32_t>(P);  // component c: comp_top - c
    std::vector<std::uint32_t> stack, vox;
    std::vector<char> touched(P, 0);
    std::vector<std::uint32_t> touched_list;
    struct Part {
      std::uint32_t label;
      bool object;
    };
    std::vector<Part> parts;
    std::vector<double> dmin(P), dmax(P), dsum(P);
    std::vector<std::uint32_t> near;  // of a part: the pieces its distances are needed for
    for (std::size_t m0 = 0; m0 < n; ++m0) {
      if (labels_[members_[m0]] != s) continue;
      const std::uint32_t label = comp_top - static_cast<std::uint32_t>(parts.size());
      vox.clear();
      stack.assign(1, members_[m0]);
      labels_[members_[m0]] = label;
      touched_list.clear();
      while (!stack.empty()) {
        const std::uint32_t w = stack.back();
        stack.pop_back();
        vox.push_back(w);
        for_neighbours(w, [&](std::size_t j) {
          const std::uint32_t l = labels_[j];
          if (l == s) {
            labels_[j] = label;
            stack.push_back(static_cast<std::uint32_t>(j));
          } else if (l > comp_top) {
            const std::size_t q = kTop - l;
            if (!touched[q]) touched[q] = 1, touched_list.push_back(static_cast<std::uint32_t>(q));
          }
        });
      }
      // Only what touches a structural piece stands on or against it; the rest (rings of returns
      // on a wall too small to be structure, joined to the shell across unknown gaps) stays.
      bool object = vox.size() >= min_object_ && !touched_list.empty();
      if (object) {
        Vec mean{0, 0, 0};
        for (const std::uint32_t w : vox) {
          const Vec c = coords(w);
          for (int k = 0; k < 3; ++k) mean[k] += c[k];
        }
        for (double& c : mean) c /= double(vox.size());
        // Only the structural pieces it touches or whose extent its mean lies over are asked
        // about its distances below: the others' are not computed.
        near.clear();
        for (std::size_t q = 0; q < P; ++q) {
          const Piece& pc = local[q];
          if (!pc.structural) continue;
          const double a = dot(mean, pc.u), b = dot(mean, pc.v);
          const bool over = a >= pc.u0 && a <= pc.u1 && b >= pc.v0 && b <= pc.v1;
          if (touched[q] || over) near.push_back(static_cast<std::uint32_t>(q));
        }
        for (const std::uint32_t q : near) dmin[q] = std::numeric_limits<double>::infinity(), dmax[q] = -dmin[q], dsum[q] = 0;
        for (const std::uint32_t w : vox) {
          const Vec c = coords(w);
          for (const std::uint32_t q : near) {
            const double e = local[q].pl.distance(c[0], c[1], c[2]);
            dmin[q] = std::min(dmin[q], e), dmax[q] = std::max(dmax[q], e), dsum[q] += e;
          }
        }
        for (const std::uint32_t q : near) {
          const Piece& pc = local[q];
          const bool flat = std::max(std::fabs(dmin[q]), std::fabs(dmax[q])) < pc.min_height;
          if (flat) object = false;  // a layer of the plane's own surface
        }
        for (const std::uint32_t q : touched_list) {
          if (!object) break;
          const Piece& pc = local[q];
          const int side = dsum[q] > 0 ? 0 : 1;
          const double height = side == 0 ? dmax[q] : -dmin[q];
          if (!pc.open[side] || height < pc.min_height) object = false;  // behind a wall, or low
        }
      }
      for (const std::uint32_t q : touched_list) touched[q] = 0;
      parts.push_back({label, object});
    }
    // Final ids: objects appended in order of first voxel; everything else is s.
    std::vector<std::uint32_t> final_id(parts.size(), s);
    for (std::size_t c = 0; c < parts.size(); ++c)
      if (parts[c].object) {
        final_id[c] = static_cast<std::uint32_t>(segs_.size());
        Segment fresh;
        fresh.id = final_id[c];
        fresh.state = State::occupied;
        fresh.kind = Kind::object;
        segs_.push_back(fresh);
      }
    std::vector<Sum> sums(segs_.size() - first_temp + 1);  // [0]: s, [1 + k]: first_temp + k
    for (std::size_t m = 0; m < n; ++m) {
      std::uint32_t& l = labels_[members_[m]];
      l = l > comp_top ? s : final_id[comp_top - l];
      sums[l == s ? 0 : 1 + (l - first_temp)].add(pts_[m], g_.value(members_[m]));
    }
    sums[0].store(segs_[s]);
    for (std::size_t k = 1; k < sums.size(); ++k) sums[k].store(segs_[first_temp + k - 1]);
    // Its structural pieces gather coplanar fragments; the rest may now be in objects. Its wide
    // pieces gather larger coplanar segments after the structural ones (attract_fragments()).
    for (const Piece& pc : local)
      if (pc.structural) pieces_.push_back(pc);
      else if (spans_extent(pc)) wide_.push_back(pc);
  }

  // Small occupied groups lying in a piece's plane, inside its extent, join its segment; the
  // others that are not structure (small ones included) join a structure segment when most of
  // their voxels lie in the planes of its structural and wide pieces (wide_), wherever in the
  // planes (see kCoplanarPercent).
  void attract_fragments() {
    if (pieces_.empty()) return;
    const std::size_t S = segs_.size();
    std::vector<std::uint32_t> into(S, ~0u);
    const double m = margin_;
    // Each structure segment's surfaces: its structural pieces, then its wide ones; the segments
    // in order of their first structural piece, then those with wide pieces only.
    std::vector<std::pair<std::uint32_t, std::vector<const Piece*>>> surfaces;
    {
      std::vector<std::uint32_t> slot(S, ~0u);
      for (const std::vector<Piece>* list : {&pieces_, &wide_})
        for (const Piece& pc : *list) {
          if (!pc.structural && list != &wide_) continue;
          if (slot[pc.segment] == ~0u) {
            slot[pc.segment] = static_cast<std::uint32_t>(surfaces.size());
            surfaces.push_back({pc.segment, {}});
          }
          surfaces[slot[pc.segment]].second.push_back(&pc);
        }
    }
    // Whether the voxels of a segment (their centres `pts`) lie within one voxel edge of these
    // planes, all but off_plane of them: of the one of each orientation that holds most of them (a
    // fragment at a corner lies in two; parallel planes, a floor's and a bench's, are not added
    // up).
    const auto lies_on = [&](const std::vector<Vec>& pts, const std::vector<const Piece*>& planes,
                             std::size_t off_plane) {
      const Piece* best[3] = {nullptr, nullptr, nullptr};
      std::size_t most[3] = {0, 0, 0};
      for (const Piece* pc : planes) {
        std::size_t n = 0;
        for (const Vec& c : pts) n += std::fabs(pc->pl.distance(c[0], c[1], c[2])) <= 1.0;
        if (n > most[pc->axis]) most[pc->axis] = n, best[pc->axis] = pc;
      }
      if (most[0] + most[1] + most[2] + off_plane < pts.size()) return false;
      std::size_t off = 0;
      for (const Vec& c : pts) {
        bool on = false;
        for (const Piece* pc : best) on = on || (pc && std::fabs(pc->pl.distance(c[0], c[1], c[2])) <= 1.0);
        off += !on;
      }
      return off <= off_plane;
    };
    // Whether they all lie in piece pc's plane, inside its extent widened by the margin.
    const auto lies_in = [&](const std::vector<Vec>& pts, const Piece& pc) {
      for (const Vec& c : pts) {
        if (std::fabs(pc.pl.distance(c[0], c[1], c[2])) > 1.0) return false;
        const double a = dot(c, pc.u), b = dot(c, pc.v);
        if (a < pc.u0 - m || a > pc.u1 + m || b < pc.v0 - m || b > pc.v1 + m) return false;
      }
      return true;
    };
    // (Segment by segment on the threads: each decision reads only the labels and the pieces.)
    parallel_for_dynamic(S, p_.threads, [&](std::size_t f0, std::size_t f1) {
      std::vector<std::uint32_t> vox;
      std::vector<Vec> pts;
      for (std::size_t f = f0; f < f1; ++f) {
        const Segment& seg = segs_[f];
        if (seg.state != State::occupied || seg.kind == Kind::structure) continue;
        // (A small one is never a candidate, so never a piece's segment.)
        const bool small = seg.voxels < min_object_ && seg.voxels < 2 * min_plane_;
        vox.clear();
        list_members(static_cast<std::uint32_t>(f), vox);
        pts.resize(vox.size());
        for (std::size_t i = 0; i < vox.size(); ++i) pts[i] = coords(vox[i]);
        if (small) {
          for (const Piece& pc : pieces_) {
            bool near = pc.segment != f;
            for (int k = 0; k < 3 && near; ++k)
              near = double(seg.bbox_max[k]) + m >= double(pc.lo[k]) && double(seg.bbox_min[k]) <= double(pc.hi[k]) + m;
            if (near && lies_in(pts, pc)) {
              into[f] = pc.segment;
              break;
            }
          }
        }
        if (into[f] == ~0u) {  // (a small one too: a speckle lying in a wall's plane, beyond its piece)
          // It may leave this many of its voxels off the planes.
          const std::size_t off_plane = vox.size() * (100 - kCoplanarPercent) / 100;
          for (const auto& [t, planes] : surfaces)
            if (t != f && lies_on(pts, planes, off_plane)) {
              into[f] = t;
              break;
            }
        }
      }
    });
    const bool any = std::any_of(into.begin(), into.end(), [](std::uint32_t t) { return t != ~0u; });
    // A small one may have joined a larger one that joined a structure segment: it goes there too
    // (structure segments join nothing, so every chain ends within two steps).
    for (std::size_t f = 0; f < S; ++f)
      if (into[f] != ~0u && into[into[f]] != ~0u) into[f] = into[into[f]];
    if (!any) return;
    // Merged statistics (voxel-weighted, members in id order), then dense ids.
    std::vector<double> mop(S), cx(S), cy(S), cz(S);
    for (std::size_t s = 0; s < S; ++s) {
      const double v = double(segs_[s].voxels);
      mop[s] = segs_[s].mop * v, cx[s] = segs_[s].centroid[0] * v, cy[s] = segs_[s].centroid[1] * v,
      cz[s] = segs_[s].centroid[2] * v;
    }
    std::vector<char> grown(S, 0);
    for (std::size_t f = 0; f < S; ++f) {
      if (into[f] == ~0u) continue;
      Segment& t = segs_[into[f]];
      const Segment& a = segs_[f];
      grown[into[f]] = 1;
      t.voxels += a.voxels;
      mop[into[f]] += mop[f], cx[into[f]] += cx[f], cy[into[f]] += cy[f], cz[into[f]] += cz[f];
      for (int k = 0; k < 3; ++k) {
        t.bbox_min[k] = std::min(t.bbox_min[k], a.bbox_min[k]);
        t.bbox_max[k] = std::max(t.bbox_max[k], a.bbox_max[k]);
      }
    }
    for (std::size_t s = 0; s < S; ++s)
      if (grown[s]) {
        const double v = double(segs_[s].voxels);
        segs_[s].mop = mop[s] / v;
        segs_[s].centroid = {cx[s] / v, cy[s] / v, cz[s] / v};
      }
    std::vector<std::uint32_t> new_id(S);
    std::vector<Segment> out;
    for (std::size_t s = 0; s < S; ++s)
      if (into[s] == ~0u) {
        new_id[s] = static_cast<std::uint32_t>(out.size());
        out.push_back(segs_[s]);
        out.back().id = new_id[s];
      }
    for (std::size_t s = 0; s < S; ++s)
      if (into[s] != ~0u) new_id[s] = new_id[into[s]];
    parallel_for(labels_.size(), p_.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) labels_[i] = new_id[labels_[i]];
    });
    segs_ = std::move(out);
  }

  const Grid& g_;
  const Dims d_;
  LabelArray& labels_;
  std::vector<Segment>& segs_;
  const Params& p_;
  const kernels::Table& k_;
  std::size_t min_plane_ = 0, min_object_ = 0;
  double extent_ = 0;
  int cell_ = 2;
  int margin_ = 1;
  VoxelNeighbours neighbours_;
  // The voxels of the segment being examined: a stretch of the bucket or of listed_ (no copy).
  struct Members {
    const std::uint32_t* p = nullptr;
    std::size_t n = 0;
    std::size_t size() const { return n; }
    std::uint32_t operator[](std::size_t i) const { return p[i]; }
  } members_;
  std::vector<std::uint32_t> listed_;
  // Pieces of split segments that are not structural but span structure_extent both ways (a
  // ceiling seen in rings too sparse to be an area): planes of structure for coplanar segments.
  std::vector<Piece> wide_;
  std::vector<Vec> pts_;
  std::vector<std::uint32_t> by_[2];  // the examined segment's voxels (into pts_) by x, by y
  // Where each row of the examined segment's voxels' box starts in pts_ (row (y, z):
  // (z - row_z0_) row_by_ + y - row_y0_), and one past the last.
  std::vector<std::uint32_t> rows_;
  long row_y0_ = 0, row_z0_ = 0, row_by_ = 0, row_bz_ = 0;
  std::vector<Piece> pieces_;  // gather fragments: unsplit segments' pieces, structural pieces
  // What search() found for apply(): the segment, each member's structural piece (index into
  // local_) or -1, its pieces of >= min_plane voxels, each member's thin axes.
  std::uint32_t s_ = 0;
  bool found_ = false;
  std::vector<std::int32_t> piece_of_;
  std::vector<Piece> local_;
  std::vector<std::uint8_t> axes_;
};

}  // namespace

void split_structure(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                     const kernels::Table& k, std::vector<PlanePiece>* pieces) {
  // (A one-layer map's walls are lines and its one layer the only "plane": nothing to find.)
  if (params.structure_planes <= 0 || params.support_plane <= 0 || segments.empty() || grid.dims.nz == 1) return;
  Structure(grid, labels, segments, params, k).run(pieces);
}

}  // namespace occseg
