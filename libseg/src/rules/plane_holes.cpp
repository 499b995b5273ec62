// Holes in a plane (rules/plane_holes.hpp): free runs between a plane piece's own voxels.
#include "rules/plane_holes.hpp"

#include <algorithm>
#include <cmath>

#include "occseg/parallel.hpp"
#include "rules/planes.hpp"

namespace occseg {

namespace {

double distance(const PlanePiece& pc, double x, double y, double z) {
  return pc.n[0] * x + pc.n[1] * y + pc.n[2] * z - pc.d;
}

class PlaneHoles {
 public:
  PlaneHoles(const Grid& g, LabelArray& labels, std::vector<Segment>& segs, int gap, int object_gap, int threads)
      : g_(g), d_(g.dims), labels_(labels), segs_(segs), gap_(gap), object_gap_(object_gap), threads_(threads) {}

  void run(const std::vector<PlanePiece>& pieces) {
    // Decided on the labels as they are: (voxel, segment it joins), each voxel once (first piece).
    std::vector<std::pair<std::uint64_t, std::uint32_t>> fill;
    std::vector<std::uint64_t> mine;
    const std::vector<char> edge_on = seen_edge_on(pieces);
    for (std::size_t q = 0; q < pieces.size(); ++q) {
      const PlanePiece& pc = pieces[q];
      const std::uint32_t target = labels_[pc.voxel];
      mine.clear();
      if (edge_on[q] && segs_[target].state == State::occupied) holes(pc, mine);
      for (const std::uint64_t i : mine) fill.emplace_back(i, target);
    }
    if (fill.empty()) return;
    // First piece wins: a stable sort by voxel keeps the pieces' order among equal voxels.
    std::stable_sort(fill.begin(), fill.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    fill.erase(std::unique(fill.begin(), fill.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
               fill.end());
    // A free segment that would lose every voxel keeps them (segments are never emptied here).
    std::vector<std::uint64_t> taken(segs_.size(), 0);
    for (const auto& f : fill) ++taken[labels_[f.first]];
    std::vector<Sum> out(segs_.size()), in(segs_.size());
    std::vector<char> on_face(segs_.size(), 0);
    for (const auto& [i, t] : fill) {
      const std::uint32_t s = labels_[i];
      if (taken[s] >= segs_[s].voxels) continue;
      const std::array<std::uint32_t, 3> c = coords(i);
      const double p = g_.value(i);
      out[s].add(c, p);
      in[t].add(c, p);
      for (int k = 0; k < 3; ++k)
        if (c[k] == segs_[s].bbox_min[k] || c[k] == segs_[s].bbox_max[k]) on_face[s] = 1;
      labels_[i] = t;
    }
    for (std::size_t s = 0; s < segs_.size(); ++s) {
      Segment& seg = segs_[s];
      if (out[s].n) {
        const double n0 = double(seg.voxels), n1 = n0 - double(out[s].n);
        seg.mop = (seg.mop * n0 - out[s].p) / n1;
        for (int k = 0; k < 3; ++k) seg.centroid[k] = (seg.centroid[k] * n0 - out[s].c[k]) / n1;
        seg.voxels -= out[s].n;
        if (on_face[s]) recompute_box(static_cast<std::uint32_t>(s));
      }
      if (in[s].n) {
        const double n0 = double(seg.voxels), n1 = n0 + double(in[s].n);
        seg.mop = (seg.mop * n0 + in[s].p) / n1;
        for (int k = 0; k < 3; ++k) {
          seg.centroid[k] = (seg.centroid[k] * n0 + in[s].c[k]) / n1;
          seg.bbox_min[k] = std::min(seg.bbox_min[k], in[s].lo[k]);
          seg.bbox_max[k] = std::max(seg.bbox_max[k], in[s].hi[k]);
        }
        seg.voxels += in[s].n;
      }
    }
  }

 private:
  struct Sum {
    std::uint64_t n = 0;
    double p = 0, c[3] = {0, 0, 0};
    std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u}, hi{0, 0, 0};
    void add(const std::array<std::uint32_t, 3>& q, double value) {
      ++n;
      p += value;
      for (int k = 0; k < 3; ++k) {
        c[k] += double(q[k]);
        lo[k] = std::min(lo[k], q[k]);
        hi[k] = std::max(hi[k], q[k]);
      }
    }
  };

  std::array<std::uint32_t, 3> coords(std::uint64_t i) const {
    return {std::uint32_t(i % d_.nx), std::uint32_t((i / d_.nx) % d_.ny), std::uint32_t(i / (d_.nx * d_.ny))};
  }

  State state(std::uint64_t i) const { return segs_[labels_[i]].state; }

  // The box of segment s from its voxels (within its old box, which holds them all).
  // (The box shrinks only where a face of it holds none of s's voxels any more: the six faces are
  // looked at first, each up to its first voxel of s, which for a large free segment, the room's
  // free space, is its first voxel or nearly; the box is scanned whole only when a face emptied.)
  void recompute_box(std::uint32_t s) {
    Segment& seg = segs_[s];
    const auto face_holds = [&](int k, std::uint32_t at) {
      std::array<std::uint32_t, 3> b0 = seg.bbox_min, b1 = seg.bbox_max;
      b0[k] = b1[k] = at;
      for (std::uint32_t z = b0[2]; z <= b1[2]; ++z)
        for (std::uint32_t y = b0[1]; y <= b1[1]; ++y) {
          const std::size_t row = g_.index(0, y, z);
          for (std::uint32_t x = b0[0]; x <= b1[0]; ++x)
            if (labels_[row + x] == s) return true;
        }
      return false;
    };
    bool same = true;
    for (int k = 0; k < 3 && same; ++k) same = face_holds(k, seg.bbox_min[k]) && face_holds(k, seg.bbox_max[k]);
    if (same) return;
    std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u}, hi{0, 0, 0};
    for (std::uint32_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
      for (std::uint32_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
        const std::size_t row = g_.index(0, y, z);
        for (std::uint32_t x = seg.bbox_min[0]; x <= seg.bbox_max[0]; ++x)
          if (labels_[row + x] == s) {
            lo = {std::min(lo[0], x), std::min(lo[1], y), std::min(lo[2], z)};
            hi = {std::max(hi[0], x), std::max(hi[1], y), std::max(hi[2], z)};
          }
      }
    seg.bbox_min = lo;
    seg.bbox_max = hi;
  }

  static int normal_axis(const PlanePiece& pc) {
    int a = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(pc.n[k]) > std::fabs(pc.n[a])) a = k;
    return a;
  }

  // The piece's inliers: its segment's voxels in its band and extent (f(index, x, y, z)).
  template <class F>
  void for_inliers(const PlanePiece& pc, F&& f) const {
    const std::uint32_t s = labels_[pc.voxel];
    for (std::uint32_t z = pc.lo[2]; z <= pc.hi[2]; ++z)
      for (std::uint32_t y = pc.lo[1]; y <= pc.hi[1]; ++y)
        for (std::uint32_t x = pc.lo[0]; x <= pc.hi[0]; ++x) {
          const std::uint64_t i = g_.index(x, y, z);
          if (labels_[i] == s && in_band(pc, x, y, z) && in_extent(pc, x, y, z)) f(i, long(x), long(y), long(z));
        }
  }

  // Which pieces are seen edge-on: rays ran in their plane, so free space lies on both of its
  // sides (from its inliers, one to three voxels along the normal's axis, the first voxel outside
  // the segment is free at least a quarter as often on each side as on the other, rule 11's open
  // sides), and no other piece of its segment lies parallel to it within kStack voxels with
  // overlapping boxes (a surface seen face-on under range noise spreads over parallel layers,
  // each a piece: the layer in front of it is free space between noise returns).
  std::vector<char> seen_edge_on(const std::vector<PlanePiece>& pieces) const {
    constexpr double kStack = 2.5, kParallel = 0.985;  // voxel edges; cos 10 degrees
    const std::size_t P = pieces.size();
    std::vector<char> ok(P, 0);
    const long lim[3] = {long(d_.nx), long(d_.ny), long(d_.nz)};
    const long stride[3] = {1, long(d_.nx), long(d_.nx * d_.ny)};
    // (The pieces on the threads: each reads the labels only.)
    parallel_for_dynamic(P, threads_, [&](std::size_t q0, std::size_t q1) {
      for (std::size_t q = q0; q < q1; ++q) {
        const PlanePiece& pc = pieces[q];
        const std::uint32_t s = labels_[pc.voxel];
        const int a = normal_axis(pc);
        std::size_t seen[2] = {0, 0};
        for_inliers(pc, [&](std::uint64_t i, long x, long y, long z) {
          const long at = a == 0 ? x : (a == 1 ? y : z);
          for (int side = 0; side < 2; ++side)
            for (long step = 1; step <= 3; ++step) {
              const long t = at + (side == 0 ? step : -step);
              if (t < 0 || t >= lim[a]) break;
              const std::uint64_t j = std::uint64_t(long(i) + (t - at) * stride[a]);
              if (labels_[j] == s) continue;
              seen[side] += segs_[labels_[j]].state == State::free;
              break;
            }
        });
        ok[q] = seen[0] > 0 && seen[1] > 0 && 4 * seen[0] >= seen[1] && 4 * seen[1] >= seen[0];
      }
    });
    std::vector<char> stacked(P, 0);
    for (std::size_t q = 0; q < P; ++q)
      for (std::size_t r = q + 1; r < P; ++r) {
        const PlanePiece &A = pieces[q], &B = pieces[r];
        if (labels_[A.voxel] != labels_[B.voxel]) continue;
        if (std::fabs(A.n[0] * B.n[0] + A.n[1] * B.n[1] + A.n[2] * B.n[2]) < kParallel) continue;
        bool overlap = true;
        for (int k = 0; k < 3 && overlap; ++k)
          overlap = A.lo[k] <= B.hi[k] + kStack && B.lo[k] <= A.hi[k] + kStack;
        if (!overlap) continue;
        const double c[3] = {0.5 * (double(A.lo[0]) + A.hi[0]), 0.5 * (double(A.lo[1]) + A.hi[1]),
                             0.5 * (double(A.lo[2]) + A.hi[2])};
        if (std::fabs(distance(B, c[0], c[1], c[2])) <= kStack) stacked[q] = stacked[r] = 1;
      }
    for (std::size_t q = 0; q < P; ++q) ok[q] = ok[q] && !stacked[q];
    return ok;
  }

  bool in_extent(const PlanePiece& pc, double x, double y, double z) const {
    const double u = pc.u[0] * x + pc.u[1] * y + pc.u[2] * z;
    const double v = pc.v[0] * x + pc.v[1] * y + pc.v[2] * z;
    return u >= pc.u0 && u <= pc.u1 && v >= pc.v0 && v <= pc.v1;
  }

  bool in_band(const PlanePiece& pc, long x, long y, long z) const {
    return std::fabs(distance(pc, double(x), double(y), double(z))) <= kPlaneInlierDistance;
  }

  // Whether the occupied voxel j (at t along the normal's axis) is thin along that axis, as rule 11
  // counts it: from the last voxel of its segment reached stepping one way to the last the other
  // way, crossing gaps of at most object_gap voxels not in it, at most max(4, object_gap + 2)
  // voxels. A table top is; a wall's ring of returns crossed by a horizontal plane is not when the
  // next ring is a gap away.
  bool thin(std::uint64_t j, long t, long lim, long stride) const {
    const std::uint32_t s = labels_[j];
    const long cap = std::max(4, object_gap_ + 2);
    long run = 1;
    for (int dir = -1; dir <= 1; dir += 2) {
      long gap = 0;
      for (long k = 1; run <= cap; ++k) {
        const long u = t + dir * k;
        if (u < 0 || u >= lim) break;
        if (labels_[std::uint64_t(long(j) + dir * k * stride)] == s) {
          run += gap + 1;
          gap = 0;
        } else if (++gap > object_gap_) {
          break;
        }
      }
    }
    return run <= cap;
  }

  // The free voxels of the piece's band and extent whose free run along an in-plane axis is a hole.
  void holes(const PlanePiece& pc, std::vector<std::uint64_t>& out) const {
    const int a = normal_axis(pc);  // the runs go along the other two grid axes
    const long lim[3] = {long(d_.nx), long(d_.ny), long(d_.nz)};
    const long stride[3] = {1, long(d_.nx), long(d_.nx * d_.ny)};
    long lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      const long w = k == a ? 1 : 0;  // the band reaches a voxel beyond the inliers along the normal
      lo[k] = std::max(0L, long(pc.lo[k]) - w);
      hi[k] = std::min(lim[k] - 1, long(pc.hi[k]) + w);
    }
    for (long z = lo[2]; z <= hi[2]; ++z)
      for (long y = lo[1]; y <= hi[1]; ++y)
        for (long x = lo[0]; x <= hi[0]; ++x) {
          const std::uint64_t i = g_.index(std::size_t(x), std::size_t(y), std::size_t(z));
          if (state(i) != State::free || !in_band(pc, x, y, z)) continue;
          if (!in_extent(pc, double(x), double(y), double(z))) continue;
          const long q[3] = {x, y, z};
          for (int b = 0; b < 3; ++b) {
            if (b == a) continue;
            // The run through i along b: its ends, the first voxels beyond it on each side.
            int run = 1, occupied = 0;
            bool closed = true;
            for (int dir = -1; dir <= 1 && closed; dir += 2) {
              long p[3] = {q[0], q[1], q[2]};
              std::uint64_t j = i;
              for (;;) {
                p[b] += dir;
                if (p[b] < 0 || p[b] >= lim[b] || !in_band(pc, p[0], p[1], p[2])) {
                  closed = false;
                  break;
                }
                j = std::uint64_t(long(j) + dir * stride[b]);
                const State s = state(j);
                if (s != State::free) {
                  occupied += s == State::occupied && thin(j, p[a], lim[a], stride[a]);
                  break;
                }
                if (++run > gap_) {
                  closed = false;
                  break;
                }
              }
            }
            if (closed && occupied > 0) {
              out.push_back(i);
              break;
            }
          }
        }
  }

  const Grid& g_;
  const Dims d_;
  LabelArray& labels_;
  std::vector<Segment>& segs_;
  const int gap_, object_gap_, threads_;
};

}  // namespace

void fill_plane_holes(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments, const Params& params,
                      const std::vector<PlanePiece>& pieces) {
  if (params.plane_holes <= 0 || pieces.empty()) return;
  PlaneHoles(grid, labels, segments, params.plane_holes, params.object_gap, params.threads).run(pieces);
}

}  // namespace occseg
