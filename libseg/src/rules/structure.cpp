// Structure and objects (rules/structure.hpp): several planes per segment, the objects standing on
// or against them, and the coplanar fragments of a surface.
#include "rules/structure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "occseg/parallel.hpp"
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

  void run() {
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
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      if (bucket.empty()) {
        list_members(candidates[c], listed_);
        members_ = {listed_.data(), listed_.size()};
      } else {
        members_ = {bucket.data() + start[c], start[c + 1] - start[c]};
      }
      examine(candidates[c]);
    }
    attract_fragments();
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
        for (std::size_t x = seg.bbox_min[0]; x <= seg.bbox_max[0]; ++x)
          if (labels_[row + x] == s) out.push_back(static_cast<std::uint32_t>(row + x));
      }
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
    std::vector<std::pair<std::int64_t, std::int64_t>> cell(inl.size());
    for (std::size_t i = 0; i < inl.size(); ++i) {
      const Vec& q = pts_[inl[i]];
      cell[i] = {static_cast<std::int64_t>(std::floor(dot(q, u) / cell_)),
                 static_cast<std::int64_t>(std::floor(dot(q, v) / cell_))};
    }
    std::vector<std::pair<std::int64_t, std::int64_t>> cells = cell;
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    std::vector<std::uint32_t> parent(cells.size());
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&](std::uint32_t a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    for (std::size_t c = 0; c < cells.size(); ++c)
      for (int du = -1; du <= 1; ++du)
        for (int dv = -1; dv <= 1; ++dv) {
          if (du < 0 || (du == 0 && dv <= 0)) continue;  // each pair once
          const std::pair<std::int64_t, std::int64_t> w{cells[c].first + du, cells[c].second + dv};
          const auto it = std::lower_bound(cells.begin(), cells.end(), w);
          if (it == cells.end() || *it != w) continue;
          std::uint32_t a = find(static_cast<std::uint32_t>(c)), b = find(static_cast<std::uint32_t>(it - cells.begin()));
          if (a == b) continue;
          if (a > b) std::swap(a, b);
          parent[b] = a;
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
    const auto has = [&](std::int64_t a, std::int64_t b) {
      return std::binary_search(cells.begin(), cells.end(), std::pair<std::int64_t, std::int64_t>{a, b});
    };
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::uint32_t k = number[find(static_cast<std::uint32_t>(c))];
      ++cells_of[k];
      const auto [a, b] = cells[c];
      inner[k] += has(a - 1, b) && has(a + 1, b) && has(a, b - 1) && has(a, b + 1);
    }
    std::vector<std::uint32_t> piece(inl.size());
    for (std::size_t i = 0; i < inl.size(); ++i) {
      const auto it = std::lower_bound(cells.begin(), cells.end(), cell[i]);
      piece[i] = number[find(static_cast<std::uint32_t>(it - cells.begin()))];
    }
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

  // A box around the points within distance t of a piece's plane over its extent widened by w
  // (a <= u . x - u0 ... ): wider than that by a voxel edge, so rounding never leaves out a point
  // the exact tests would take. at(i0 .. i1): the voxels of the segment (indices into pts_) in its
  // range along the axis that has the fewest there, in order along it (pts_ is in scan order, so
  // by z; by_ holds the orders by x and by y). Its users' results do not depend on the order.
  struct Box {
    double lo[3], hi[3];
    const std::uint32_t* order = nullptr;  // nullptr: scan order
    std::size_t i0 = 0, i1 = 0;
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
    return b;
  }

  // Robust spread of a plane's surface: 1.4826 x the median |distance| of the segment's voxels
  // within 4 voxel edges of it and over the piece's extent (as rules/planes.cpp).
  double surface_sigma(const Piece& pc) const {
    std::vector<double> near;
    const Box box = band_box(pc, 4.0, 0.0);
    for (std::size_t i = box.i0; i < box.i1; ++i) {
      const Vec& q = pts_[box.at(i)];
      if (!box.holds(q)) continue;
      const double e = std::fabs(pc.pl.distance(q[0], q[1], q[2]));
      if (e > 4.0) continue;
      const double a = dot(q, pc.u), b = dot(q, pc.v);
      if (a < pc.u0 || a > pc.u1 || b < pc.v0 || b > pc.v1) continue;
      near.push_back(e);
    }
    if (near.empty()) return 0;
    std::nth_element(near.begin(), near.begin() + std::ptrdiff_t(near.size() / 2), near.end());
    return 1.4826 * near[near.size() / 2];
  }

  void examine(std::uint32_t s) {
    const std::size_t n = members_.size();
    // Each voxel's possible orientations: axis a when the segment is thin along a through it
    // (thickness() at most max(4, object_gap + 2) voxels: a floor along z, a wall along its
    // normal). A horizontal ring of returns on a wall is thick along z (the rings above and below
    // it) and is never searched as a horizontal plane; a floor's voxels are.
    // The planes are searched among the voxels of one orientation at a time (z: floors, ceilings,
    // table tops first; then y, then x): a plane within 45 degrees of an axis is found among that
    // axis' voxels.
    const int thin = std::max(4, p_.object_gap + 2);
    // A segment whose voxels are mostly thick along every axis (a sprawling region of noise) holds
    // no surfaces: judged on an evenly strided sample of at most 4096 of its voxels before any
    // work per voxel.
    {
      const std::size_t k = std::min<std::size_t>(n, 4096);
      std::size_t surface = 0;
      for (std::size_t i = 0; i < k; ++i) {
        const Vec q = coords(members_[i * n / k]);
        for (int a = 0; a < 3; ++a)
          if (thickness(s, q, a, thin + 1) <= thin) {
            ++surface;
            break;
          }
      }
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
    std::vector<std::int32_t> piece_of(n, -1);  // structural piece (index into local) or -1
    std::vector<Piece> local;                   // this segment's pieces of >= min_plane voxels
    std::vector<std::uint8_t> axes(n, 0);
    for (std::size_t m = 0; m < n; ++m)
      for (int a = 0; a < 3; ++a)
        if (thickness(s, pts_[m], a, thin + 1) <= thin) axes[m] |= std::uint8_t(1u << a);
    std::vector<std::uint32_t> rest;
    std::vector<Vec> rpts;
    std::vector<std::uint32_t> inl, keep, positions;
    for (int axis = 2, it = 0; axis >= 0; --axis) {
      rest.clear();
      for (std::size_t m = 0; m < n; ++m)
        if ((axes[m] >> axis & 1) && piece_of[m] < 0) rest.push_back(static_cast<std::uint32_t>(m));
      for (int tries = 0; tries < p_.structure_planes && rest.size() >= min_plane_; ++tries, ++it) {
      rpts.resize(rest.size());
      for (std::size_t r = 0; r < rest.size(); ++r) rpts[r] = pts_[rest[r]];
      Plane pl;
      std::size_t count = 0;
      const std::uint64_t seed = 0x737472756374ull ^ (std::uint64_t(members_[0]) * 0x9E3779B97F4A7C15ull) ^
                                 (std::uint64_t(it) * 0xD1B54A32D192ED03ull);
      if (!fit_dominant_plane(rpts, seed, pl, count, 1, k_, axis, &positions) || count < min_plane_) break;
      if (std::fabs(pl.n[std::size_t(axis)]) < std::sqrt(0.5)) break;  // (refitted away from the axis)
      // The plane's inliers among the rest (the fit's, in order), and what stays.
      inl.clear();
      keep.clear();
      for (std::size_t r = 0, i = 0; r < rest.size(); ++r)
        if (i < positions.size() && positions[i] == r)
          inl.push_back(rest[r]), ++i;
        else
          keep.push_back(rest[r]);
      rest.swap(keep);
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
        if (pc.voxels == 0) pc.lo = pc.hi = {std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2])};
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
        pc.segment = s, pc.pl = pl;
        // Structural: wide both ways, an area (at least a quarter of its cells inner ones), and flat.
        pc.structural = pc.u1 - pc.u0 + 1 >= extent_ && pc.v1 - pc.v0 + 1 >= extent_ && 4 * inner[q] >= cells_of[q];
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
      for (std::size_t i = box.i0; i < box.i1; ++i) {
        const std::size_t m = box.at(i);
        if (piece_of[m] >= 0) continue;
        const Vec& q = pts_[m];
        if (!box.holds(q) || std::fabs(pc.pl.distance(q[0], q[1], q[2])) > kPlaneInlierDistance) continue;
        const double a = dot(q, pc.u), b = dot(q, pc.v);
        if (a < pc.u0 - w || a > pc.u1 + w || b < pc.v0 - w || b > pc.v1 + w) continue;
        piece_of[m] = static_cast<std::int32_t>(p);
      }
    }
    const bool structural = std::any_of(local.begin(), local.end(), [](const Piece& pc) { return pc.structural; });
    if (!structural) {  // unsplit: its pieces still gather coplanar fragments
      pieces_.insert(pieces_.end(), local.begin(), local.end());
      return;
    }
    segs_[s].kind = Kind::structure;
    split(s, local, piece_of);
  }

  // Temporary labels, above every id: structural pieces kTop - q, remainder components below them.
  void split(std::uint32_t s, std::vector<Piece>& local, const std::vector<std::int32_t>& piece_of) {
    const std::size_t n = members_.size(), P = local.size();
    for (std::size_t m = 0; m < n; ++m)
      if (piece_of[m] >= 0) labels_[members_[m]] = kTop - static_cast<std::uint32_t>(piece_of[m]);
    const std::uint32_t first_temp = static_cast<std::uint32_t>(segs_.size());  // temporaries are above
    const auto member = [&](std::uint32_t l) { return l == s || l >= first_temp; };
    for (std::size_t q = 0; q < P; ++q) {
      Piece& pc = local[q];
      if (!pc.structural) continue;
      pc.min_height = std::max(kMinObjectHeight, kNoiseHeights * surface_sigma(pc));
    }
    // Open sides: from each structural voxel, one to three voxels along +n and -n, the first voxel
    // outside the segment; a side is open when it saw free space at least a quarter as often as
    // the other (a wall between two rooms is open on both).
    std::vector<std::array<std::size_t, 2>> seen(P, {0, 0});
    for (std::size_t m = 0; m < n; ++m) {
      if (piece_of[m] < 0) continue;
      const Piece& pc = local[std::size_t(piece_of[m])];
      for (int side = 0; side < 2; ++side)
        for (int step = 1; step <= 3; ++step) {
          std::size_t w;
          if (!voxel_at(pts_[m], (side == 0 ? 1.0 : -1.0) * step, pc.pl.n, w)) break;
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
      sums[l == s ? 0 : 1 + (l - first_temp)].add(pts_[m], g_.values()[members_[m]]);
    }
    sums[0].store(segs_[s]);
    for (std::size_t k = 1; k < sums.size(); ++k) sums[k].store(segs_[first_temp + k - 1]);
    // Its structural pieces gather coplanar fragments; the rest may now be in objects.
    for (const Piece& pc : local)
      if (pc.structural) pieces_.push_back(pc);
  }

  // Small occupied groups lying in a piece's plane, inside its extent, join its segment.
  void attract_fragments() {
    if (pieces_.empty()) return;
    const std::size_t S = segs_.size();
    std::vector<std::uint32_t> into(S, ~0u);
    bool any = false;
    std::vector<std::uint32_t> vox;
    const double m = margin_;
    for (std::size_t f = 0; f < S; ++f) {
      const Segment& seg = segs_[f];
      if (seg.state != State::occupied || seg.kind == Kind::structure || seg.voxels >= min_object_ ||
          seg.voxels >= 2 * min_plane_)  // (never a candidate, so never a piece's segment)
        continue;
      vox.clear();
      list_members(static_cast<std::uint32_t>(f), vox);
      for (const Piece& pc : pieces_) {
        bool near = true;
        for (int k = 0; k < 3 && near; ++k)
          near = double(seg.bbox_max[k]) + m >= double(pc.lo[k]) && double(seg.bbox_min[k]) <= double(pc.hi[k]) + m;
        if (!near || pc.segment == f) continue;
        bool inside = true;
        for (std::size_t i = 0; i < vox.size() && inside; ++i) {
          const Vec c = coords(vox[i]);
          const double a = dot(c, pc.u), b = dot(c, pc.v);
          inside = std::fabs(pc.pl.distance(c[0], c[1], c[2])) <= 1.0 && a >= pc.u0 - m && a <= pc.u1 + m &&
                   b >= pc.v0 - m && b <= pc.v1 + m;
        }
        if (!inside) continue;
        into[f] = pc.segment;
        any = true;
        break;
      }
    }
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
  std::vector<Vec> pts_;
  std::vector<std::uint32_t> by_[2];  // the examined segment's voxels (into pts_) by x, by y
  std::vector<Piece> pieces_;  // gather fragments: unsplit segments' pieces, structural pieces
};

}  // namespace

void split_structure(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                     const kernels::Table& k) {
  // (A one-layer map's walls are lines and its one layer the only "plane": nothing to find.)
  if (params.structure_planes <= 0 || params.support_plane <= 0 || segments.empty() || grid.dims.nz == 1) return;
  Structure(grid, labels, segments, params, k).run();
}

}  // namespace occseg
