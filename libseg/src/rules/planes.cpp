// Support planes (rules/planes.hpp): a segment's dominant plane by MSAC, and the split of the
// objects standing on it.
#include "rules/planes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "occseg/parallel.hpp"
#include "rules/box_rows.hpp"
#include "rules/neighbours.hpp"

namespace occseg {

namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// splitmix64: a fixed, portable sequence, so a map splits the same way on every machine.
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

// Eigenvector of the smallest eigenvalue of a symmetric 3 x 3 matrix (cyclic Jacobi rotations):
// the normal of the least-squares plane through points with that scatter matrix.
Vec smallest_eigenvector(double a[3][3]) {
  double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if (off < 1e-30) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a <- a J (columns p, q)
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // a <- J^T a (rows p, q)
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  int m = 0;
  for (int k = 1; k < 3; ++k)
    if (a[k][k] < a[m][m]) m = k;
  return {v[0][m], v[1][m], v[2][m]};
}

std::size_t count_inliers(const std::vector<Vec>& pts, const Plane& pl) {
  std::size_t c = 0;
  for (const Vec& p : pts) c += std::fabs(pl.distance(p[0], p[1], p[2])) <= kPlaneInlierDistance;
  return c;
}

// MSAC cost: squared distances, capped at the inlier distance. Counting inliers alone would
// prefer a slightly tilted plane that also grazes a few voxels of the layer above it.
//
// The terms are summed in four lanes (point i into lane i % 4, each lane in point order) and
// the cost is (l0 + l1) + (l2 + l3): the same sum whether a kernel computes four points at a time
// or one (kernels::PlanesKernels::cost, which scores the search's sample and the refits over all
// points, stopping once the sum reaches a bound).
constexpr double kCap = kPlaneInlierDistance * kPlaneInlierDistance;

// The plane search's sample by coordinate, for the cost kernels' vector loads.
struct Coords {
  std::size_t n;
  std::unique_ptr<double[]> x, y, z;  // (not zeroed first: every element is written)
  explicit Coords(const std::vector<Vec>& pts)
      : n(pts.size()), x(new double[pts.size()]), y(new double[pts.size()]), z(new double[pts.size()]) {
    for (std::size_t i = 0; i < n; ++i) x[i] = pts[i][0], y[i] = pts[i][1], z[i] = pts[i][2];
  }
  kernels::PlanePoints points() const { return {x.get(), y.get(), z.get(), n}; }
};

kernels::MsacPlane msac(const Plane& pl) { return {pl.n[0], pl.n[1], pl.n[2], pl.d}; }

// The cost of `pl` on the sample in `c`, cut short from `stop` on.
double sample_cost(const kernels::PlanesKernels& k, const Coords& c, const Plane& pl, double stop) {
  return k.cost(c.points(), msac(pl), kCap, stop);
}

// sample_cost() of two planes.
void sample_cost_pair(const kernels::PlanesKernels& k, const Coords& c, const Plane& a, const Plane& b, double stop,
                      double& cost_a, double& cost_b) {
  k.cost_pair(c.points(), msac(a), msac(b), kCap, stop, cost_a, cost_b);
}

// Least-squares plane through the points of `pts` at positions `inl` (ascending: the sums run in
// point order); false if degenerate. (The scatter matrix's lower triangle is its upper one:
// q[a] * q[b] and q[b] * q[a] are the same product, summed in the same order.)
bool refit(const kernels::PlanePoints& pts, const std::uint32_t* inl, std::size_t n, Plane& out) {
  Vec mean{0, 0, 0};
  for (std::size_t j = 0; j < n; ++j) mean[0] += pts.x[inl[j]], mean[1] += pts.y[inl[j]], mean[2] += pts.z[inl[j]];
  if (n < 3) return false;
  for (double& m : mean) m /= double(n);
  double c00 = 0, c01 = 0, c02 = 0, c11 = 0, c12 = 0, c22 = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const double q0 = pts.x[inl[j]] - mean[0], q1 = pts.y[inl[j]] - mean[1], q2 = pts.z[inl[j]] - mean[2];
    c00 += q0 * q0, c01 += q0 * q1, c02 += q0 * q2, c11 += q1 * q1, c12 += q1 * q2, c22 += q2 * q2;
  }
  double c[3][3] = {{c00, c01, c02}, {c01, c11, c12}, {c02, c12, c22}};
  const Vec nrm = smallest_eigenvector(c);
  const double len = std::sqrt(dot(nrm, nrm));
  if (!(len > 0.5)) return false;
  out.n = {nrm[0] / len, nrm[1] / len, nrm[2] / len};
  out.d = dot(out.n, mean);
  return true;
}

}  // namespace

namespace {

// Hypotheses are scored on an evenly strided sample: a plane holding a fraction f of the points
// holds about f of the sample, and scoring costs no more for a floor of a million voxels.
constexpr std::size_t kSample = 4096;

// Indices of the sample: all of n when n <= kSample, else kSample evenly strided.
template <typename F>
void for_sample(std::size_t n, F&& f) {
  if (n <= kSample)
    for (std::size_t i = 0; i < n; ++i) f(i);
  else
    for (std::size_t i = 0; i < kSample; ++i) f(i * n / kSample);
}

// MSAC over the sample; false when every draw was degenerate. The draws are made first (the
// generator's sequence does not depend on the scores) and scored in batches, in parallel over
// `threads`; the batch's scores are then taken in draw order exactly as one at a time would, so
// the result never depends on the thread count. A batch past the adaptive stop is wasted work,
// not a different result.
bool sample_plane(const std::vector<Vec>& sample, std::uint64_t seed, Plane& best, int threads,
                  const kernels::PlanesKernels& k, int axis = -1) {
  if (sample.size() < 3) return false;
  Rng rng{seed};
  // At most 256 draws of 3 points: a plane holding half the points is drawn with probability
  // 1 - (7/8)^256 > 1 - 1e-14.
  constexpr int kDraws = 256;
  struct Draw {
    Plane h;
    bool valid = false;  // false: a repeated or collinear draw
    double score = 0;
  };
  std::vector<Draw> draws(kDraws);
  for (Draw& dr : draws) {
    const Vec& a = sample[rng.below(sample.size())];
    const Vec& b = sample[rng.below(sample.size())];
    const Vec& c = sample[rng.below(sample.size())];
    const Vec nrm = cross(sub(b, a), sub(c, a));
    const double len = std::sqrt(dot(nrm, nrm));
    if (len < 1e-9) continue;
    // (With an axis, only planes whose normal lies within 45 degrees of it are drawn; the
    // generator's sequence is the same either way.)
    if (axis >= 0 && std::fabs(nrm[static_cast<std::size_t>(axis)]) < std::sqrt(0.5) * len) continue;
    dr.valid = true;
    dr.h.n = {nrm[0] / len, nrm[1] / len, nrm[2] / len};
    dr.h.d = dot(dr.h.n, a);
  }
  const bool parallel = resolve_threads(threads) > 1;
  const Coords coords(sample);
  double best_cost = std::numeric_limits<double>::infinity();
  // Adaptive stop: once the best plane holds a fraction w of the sample, a better one would have
  // been drawn with probability 1 - (1 - w^3)^k after k draws; stop when that exceeds 1 - 1e-9
  // (13 draws for a clean plane holding 90 %, 155 for one holding half).
  int needed = kDraws;
  for (int it = 0; it < needed;) {
    // Two draws at a time on one thread (scored side by side); on more, 16 (a clean plane stops
    // after 13), then all that the stop so far still asks for. A draw scored against an earlier
    // stop than the best so far decides the same: its score, cut short or not, is below that best
    // only when it is exact.
    const int end = !parallel ? std::min(needed, it + 2) : std::min(needed, it == 0 ? 16 : kDraws);
    const double stop = best_cost;  // scores from `stop` up cannot win: cut short
    const auto score = [&](std::size_t b, std::size_t e) {
      Draw* pending = nullptr;  // a valid draw waiting for a second
      for (std::size_t d = b; d < e; ++d) {
        if (!draws[d].valid) continue;
        if (!pending) {
          pending = &draws[d];
          continue;
        }
        sample_cost_pair(k, coords, pending->h, draws[d].h, stop, pending->score, draws[d].score);
        pending = nullptr;
      }
      if (pending) pending->score = sample_cost(k, coords, pending->h, stop);
    };
    if (parallel)
      parallel_for(static_cast<std::size_t>(end - it), threads,
                   [&](std::size_t b, std::size_t e) { score(it + b, it + e); });
    else
      score(static_cast<std::size_t>(it), static_cast<std::size_t>(end));
    for (; it < end && it < needed; ++it) {
      const Draw& dr = draws[static_cast<std::size_t>(it)];
      if (!dr.valid || !(dr.score < best_cost)) continue;
      best_cost = dr.score, best = dr.h;
      const double w = double(count_inliers(sample, dr.h)) / double(sample.size());
      if (w > 0.3) needed = std::min(kDraws, static_cast<int>(std::ceil(std::log(1e-9) / std::log1p(-w * w * w))));
    }
  }
  return std::isfinite(best_cost);
}

// Two least-squares refits over all points: the best draw passes through three noisy voxels, the
// fit through all its inliers sits in the middle of a thick layer. Returns the inlier count; `inl`
// receives the inliers' positions in `points`, ascending. The costs are the kernels' (cost()'s
// sum bit for bit), a refit's cut short once it cannot beat the plane it refits; each pass lists
// its plane's inliers as it sums the cost (cost_inliers), so the plane kept has its inliers
// listed already.
std::size_t refine_plane(const kernels::PlanePoints& all, Plane& best, const kernels::PlanesKernels& k,
                         std::vector<std::uint32_t>& inl) {
  const std::unique_ptr<std::uint32_t[]> buffer(new std::uint32_t[2 * all.n + 1]);
  std::uint32_t* listed = buffer.get();       // best's inliers, n of them
  std::uint32_t* trial = listed + all.n;      // a refit's
  std::size_t n = 0, m = 0;
  double best_cost =
      k.cost_inliers(all, msac(best), kCap, std::numeric_limits<double>::infinity(), kPlaneInlierDistance, listed, n);
  for (int r = 0; r < 2; ++r) {
    Plane fit;
    if (!refit(all, listed, n, fit)) break;
    const double c = k.cost_inliers(all, msac(fit), kCap, best_cost, kPlaneInlierDistance, trial, m);
    if (!(c < best_cost)) break;
    best = fit, best_cost = c, n = m;
    std::swap(listed, trial);
  }
  inl.assign(listed, listed + n);
  return n;
}

std::size_t refine_plane(const std::vector<Vec>& points, Plane& best, const kernels::PlanesKernels& k,
                         std::vector<std::uint32_t>& inl) {
  const Coords all(points);
  return refine_plane(all.points(), best, k, inl);
}

}  // namespace

double detail::msac_cost(const std::vector<Vec>& points, const Plane& plane, const kernels::Table& k) {
  return sample_cost(k.planes, Coords(points), plane, std::numeric_limits<double>::infinity());
}

void detail::msac_cost_pair(const std::vector<Vec>& points, const Plane& a, const Plane& b, double stop, double& cost_a,
                            double& cost_b, const kernels::Table& k) {
  sample_cost_pair(k.planes, Coords(points), a, b, stop, cost_a, cost_b);
}

bool fit_dominant_plane(const std::vector<Vec>& points, std::uint64_t seed, Plane& plane, std::size_t& inliers,
                        int threads, const kernels::Table& k, int axis, std::vector<std::uint32_t>* positions) {
  const Coords all(points);
  return fit_dominant_plane(all.points(), seed, plane, inliers, threads, k, axis, positions);
}

bool fit_dominant_plane(const kernels::PlanePoints& points, std::uint64_t seed, Plane& plane, std::size_t& inliers,
                        int threads, const kernels::Table& k, int axis, std::vector<std::uint32_t>* positions) {
  inliers = 0;
  std::vector<Vec> sample;
  for_sample(points.n, [&](std::size_t i) { sample.push_back({points.x[i], points.y[i], points.z[i]}); });
  if (positions) positions->clear();
  if (!sample_plane(sample, seed, plane, threads, k.planes, axis)) return false;
  std::vector<std::uint32_t> own;
  inliers = refine_plane(points, plane, k.planes, positions ? *positions : own);
  return true;
}

namespace {

// One pass of the split over segment `s`; state shared between its steps.
class Splitter {
 public:
  Splitter(const Grid& g, LabelArray& labels, std::vector<Segment>& segments, bool occupied26,
           const kernels::PlanesKernels& k)
      : g_(g), d_(g.dims), labels_(labels), segs_(segments), k_(k),
        neighbours_(g.dims, occupied26) {}

  // Examines segment `s`. Its voxels are [first, last) in scan order when the caller bucketed
  // them, else (first = nullptr) they are found by scanning its box.
  // fit_dominant_plane() and the split in two steps. The first, search(), finds the plane of s's
  // sample and rejects a segment whose sample shows no plane near half of it (a sprawling noisy
  // region) before its voxels are even listed; then the refits over all of s's voxels and the
  // side free space is seen from. It reads the labels and the segment table only, into buffers of
  // its own, so several segments may be searched at once while none is being split (the refits
  // and the sides are most of a serial split's work).
  struct Found {
    bool split = false;  // a plane to split at: refined, holding half of s, seen from one side
    Plane pl;
    int open = 0;  // open_side()
    double min_height = 0;
  };
  Found search(std::uint32_t s, const std::uint32_t* first, const std::uint32_t* last, std::size_t min_plane,
               int threads) const {
    const std::size_t n = first ? static_cast<std::size_t>(last - first) : segs_[s].voxels;
    std::vector<std::size_t> ranks;
    for_sample(n, [&](std::size_t i) { ranks.push_back(i); });
    std::vector<Vec> pts;
    std::uint32_t first_voxel = 0;
    collect_sample(s, first, ranks, first_voxel, pts, threads);
    Found f;
    Plane pl;
    if (!sample_plane(pts, 0x6F6363736567ull ^ (std::uint64_t(first_voxel) * 0x9E3779B97F4A7C15ull), pl, threads,
                      k_) ||
        10 * count_inliers(pts, pl) < 4 * pts.size())  // under 40 %: far from half
      return f;
    std::vector<std::uint32_t> members;
    list_members(s, first, last, members);
    std::vector<Vec> all(n);
    for (std::size_t m = 0; m < n; ++m) all[m] = coords(members[m]);
    std::vector<std::uint32_t> inl;
    const std::size_t inliers = refine_plane(all, pl, k_, inl);
    if (inliers < min_plane || 2 * inliers < n) return f;
    f.open = open_side(s, pl, all);
    if (f.open == 0) return f;
    f.min_height = std::max(kMinObjectHeight, kNoiseHeights * surface_sigma(pl, all));
    f.pl = pl;
    f.split = true;
    return f;
  }

  // The second step with what search() found for s: the split itself.
  void split(std::uint32_t s, const std::uint32_t* first, const std::uint32_t* last, const Found& found) {
    if (!found.split) return;
    segs_[s].kind = Kind::structure;  // it lies mostly on a support plane, split or not
    list_members(s, first, last, members_);
    pts_.resize(members_.size());
    for (std::size_t m = 0; m < members_.size(); ++m) pts_[m] = coords(members_[m]);
    plane_ = found.pl;
    make_pieces(s);
    std::vector<std::size_t> split;
    for (std::size_t k = 0; k < pieces_.size(); ++k) {
      const Piece& p = pieces_[k];
      const double height = found.open > 0 ? p.distance_max : -p.distance_min;
      if (!p.on_plane && p.voxels >= kMinObjectVoxels && found.open * p.distance_sum > 0 && height >= found.min_height)
        split.push_back(k);
    }
    if (split.empty()) {
      for (std::uint32_t v : members_) labels_[v] = s;
      return;
    }
    relabel(s, split);
  }

 private:
  struct Piece {
    bool on_plane;
    std::size_t voxels = 0;
    double distance_sum = 0;
    double distance_min = std::numeric_limits<double>::infinity(), distance_max = -distance_min;
    std::uint32_t first = 0;
  };
  static constexpr std::uint32_t kKeep = std::numeric_limits<std::uint32_t>::max();
  static std::uint32_t temp(std::size_t k) { return kKeep - 1 - static_cast<std::uint32_t>(k); }

  Vec coords(std::size_t i) const {
    return {double(i % d_.nx), double((i / d_.nx) % d_.ny), double(i / (d_.nx * d_.ny))};
  }

  // The coordinates of the voxels of s with the given ranks (ascending) in scan order, into pts.
  // Without a bucket, rows are counted with the row_members kernel (on `threads` threads) and only
  // the few rows that hold a sampled rank are walked voxel by voxel (a branch per voxel of the
  // sprawling boxes of a noisy map is slow).
  void collect_sample(std::uint32_t s, const std::uint32_t* first, const std::vector<std::size_t>& ranks,
                      std::uint32_t& first_voxel, std::vector<Vec>& pts, int threads) const {
    if (first) {
      first_voxel = first[0];
      for (std::size_t r : ranks) pts.push_back(coords(first[r]));
      return;
    }
    const Segment& seg = segs_[s];
    const std::size_t x0 = seg.bbox_min[0], x1 = seg.bbox_max[0] + 1;
    const std::vector<std::uint32_t> counts = box_row_members(d_, labels_.data(), seg, s, threads, k_);
    const std::size_t rows_y = std::size_t(seg.bbox_max[1] - seg.bbox_min[1]) + 1;
    std::vector<std::uint64_t> bits((x1 - x0 + 63) / 64);
    std::size_t rank = 0, next = 0;
    for (std::size_t r = 0; r < counts.size() && next < ranks.size(); ++r) {
      if (rank + counts[r] <= ranks[next]) {  // (never the first row with a voxel of s: ranks[0] is 0)
        rank += counts[r];
        continue;
      }
      const std::size_t row = g_.index(0, seg.bbox_min[1] + r % rows_y, seg.bbox_min[2] + r / rows_y);
      k_.row_members(labels_.data() + row, x0, x1, s, bits.data());
      for (std::size_t k = 0; k < bits.size(); ++k)
        for (std::uint64_t w = bits[k]; w; w &= w - 1) {
          const std::size_t x = x0 + 64 * k + static_cast<std::size_t>(__builtin_ctzll(w));
          if (rank == 0) first_voxel = static_cast<std::uint32_t>(row + x);
          if (next < ranks.size() && ranks[next] == rank) pts.push_back(coords(row + x)), ++next;
          ++rank;
        }
    }
  }

  // members = the voxels of s in scan order: the bucket, or a scan of its box.
  void list_members(std::uint32_t s, const std::uint32_t* first, const std::uint32_t* last,
                    std::vector<std::uint32_t>& members) const {
    if (first) {
      members.assign(first, last);
      return;
    }
    members.clear();
    const Segment& seg = segs_[s];
    const std::size_t x0 = seg.bbox_min[0], x1 = seg.bbox_max[0] + 1;
    std::vector<std::uint64_t> bits((x1 - x0 + 63) / 64);
    for (std::size_t z = seg.bbox_min[2]; z <= seg.bbox_max[2]; ++z)
      for (std::size_t y = seg.bbox_min[1]; y <= seg.bbox_max[1]; ++y) {
        const std::size_t row = g_.index(0, y, z);
        if (!k_.row_members(labels_.data() + row, x0, x1, s, bits.data())) continue;
        for (std::size_t k = 0; k < bits.size(); ++k)
          for (std::uint64_t w = bits[k]; w; w &= w - 1) {
            const std::size_t x = x0 + 64 * k + static_cast<std::size_t>(__builtin_ctzll(w));
            members.push_back(static_cast<std::uint32_t>(row + x));
          }
      }
  }

  // +1 or -1: the side of the plane (along n) on which its voxels see free space, counted one to
  // three voxels away along the normal, past the plane's own thickness; 0 when neither side has
  // at least twice the free sightings of the other (a plane seen from both sides, or not at all).
  // (pts: the coordinates of s's voxels.)
  int open_side(std::uint32_t s, const Plane& pl, const std::vector<Vec>& pts) const {
    std::size_t seen[2] = {0, 0};
    for (const Vec& c : pts) {
      if (std::fabs(pl.distance(c[0], c[1], c[2])) > kPlaneInlierDistance) continue;
      for (int side = 0; side < 2; ++side) {
        const double sign = side == 0 ? 1.0 : -1.0;
        for (int step = 1; step <= 3; ++step) {
          std::size_t w;
          if (!voxel_at(c, sign * step, pl.n, w)) break;
          if (labels_[w] == s) continue;
          seen[side] += segs_[labels_[w]].state == State::free;
          break;
        }
      }
    }
    if (seen[0] > 0 && seen[0] >= 2 * seen[1]) return 1;
    if (seen[1] > 0 && seen[1] >= 2 * seen[0]) return -1;
    return 0;
  }

  // Robust spread of the plane's surface along its normal: 1.4826 x the median |distance| of the
  // voxels within 4 voxel edges of it (a normal distribution's sigma; objects far above do not
  // count).
  double surface_sigma(const Plane& pl, const std::vector<Vec>& pts) const {
    std::vector<double> near;
    for (const Vec& c : pts) {
      const double e = std::fabs(pl.distance(c[0], c[1], c[2]));
      if (e <= 4.0) near.push_back(e);
    }
    if (near.empty()) return 0;
    std::nth_element(near.begin(), near.begin() + near.size() / 2, near.end());
    return 1.4826 * near[near.size() / 2];
  }

  bool voxel_at(const Vec& c, double t, const Vec& n, std::size_t& out) const {
    const double q[3] = {std::round(c[0] + t * n[0]), std::round(c[1] + t * n[1]), std::round(c[2] + t * n[2])};
    const double lim[3] = {double(d_.nx), double(d_.ny), double(d_.nz)};
    for (int k = 0; k < 3; ++k)
      if (q[k] < 0 || q[k] >= lim[k]) return false;
    out = g_.index(std::size_t(q[0]), std::size_t(q[1]), std::size_t(q[2]));
    return true;
  }

  // The neighbours of voxel i inside the map, in VoxelNeighbours' order.
  template <class F>
  void for_neighbours(std::size_t i, F&& f) const {
    neighbours_.for_each(i, f);
  }

  // Flood-fills the voxels labelled `from` connected to `seed`, writing `to`; calls visit(voxel)
  // for each.
  template <class Visit>
  void flood(std::uint32_t seed, std::uint32_t from, std::uint32_t to, Visit&& visit) {
    stack_.assign(1, seed);
    labels_[seed] = to;
    while (!stack_.empty()) {
      const std::uint32_t v = stack_.back();
      stack_.pop_back();
      visit(v);
      for_neighbours(v, [&](std::size_t w) {
        if (labels_[w] == from) {
          labels_[w] = to;
          stack_.push_back(static_cast<std::uint32_t>(w));
        }
      });
    }
  }

  // Connected pieces of the plane's inliers and of the rest, each labelled temp(k). The inliers
  // are relabelled kKeep first (free until relabel()), the rest stay s, so the floods compare
  // labels only, not each neighbour's side of the plane.
  void make_pieces(std::uint32_t s) {
    pieces_.clear();
    for (std::size_t m = 0; m < members_.size(); ++m)
      if (std::fabs(plane_.distance(pts_[m][0], pts_[m][1], pts_[m][2])) <= kPlaneInlierDistance)
        labels_[members_[m]] = kKeep;
    for (std::uint32_t v : members_) {
      const std::uint32_t from = labels_[v];
      if (from != s && from != kKeep) continue;
      Piece p;
      p.on_plane = from == kKeep;
      p.first = v;
      flood(v, from, temp(pieces_.size()), [&](std::uint32_t w) {
              const Vec c = coords(w);
              const double dist = plane_.distance(c[0], c[1], c[2]);
              ++p.voxels;
              p.distance_sum += dist;
              p.distance_min = std::min(p.distance_min, dist);
              p.distance_max = std::max(p.distance_max, dist);
            });
      pieces_.push_back(p);
    }
  }

  // Split pieces and the connected components of what stays get their final ids: the component
  // holding the segment's first voxel keeps `s`, the others are appended in order of first voxel.
  void relabel(std::uint32_t s, const std::vector<std::size_t>& split) {
    std::vector<char> is_split(pieces_.size(), 0);
    for (std::size_t k : split) is_split[k] = 1;
    for (std::uint32_t v : members_)
      if (!is_split[kKeep - 1 - labels_[v]]) labels_[v] = kKeep;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> parts;  // (first voxel, temporary label)
    for (std::size_t k : split) parts.push_back({pieces_[k].first, temp(k)});
    std::size_t next = pieces_.size();
    // Kept components after the first: one that touches no split piece was not cut off by the
    // split (rule 6 joined it to the rest across unknown gaps: rings of returns on a ceiling) and
    // stays in s; one that does was cut off, and becomes a segment of its own, or joins the first
    // split piece it touches when smaller than an object (a few voxels under an overhang).
    std::vector<std::size_t> join(pieces_.size(), 0);  // for kept components: piece index + 1
    for (std::uint32_t v : members_) {
      if (labels_[v] != kKeep) continue;
      std::vector<std::uint32_t> voxels;
      flood(v, kKeep, temp(next), [&](std::uint32_t w) { voxels.push_back(w); });
      std::size_t into = 0;  // the first split piece it touches, + 1
      if (next > pieces_.size())
        for (std::size_t i = 0; i < voxels.size() && !into; ++i)
          for_neighbours(voxels[i], [&](std::size_t w) {
            const std::uint32_t l = labels_[w];
            if (!into && l > kKeep - 1 - pieces_.size() && l < kKeep && is_split[kKeep - 1 - l]) into = kKeep - l;
          });
      const bool cut_off = into != 0;
      if (voxels.size() >= kMinObjectVoxels) into = 0;
      join.push_back(into);
      if (cut_off && !into) parts.push_back({v, temp(next)});
      ++next;
    }
    std::sort(parts.begin(), parts.end());
    // The first kept component (it holds the first kept voxel) keeps the id; it is never empty:
    // the plane's inliers stay.
    std::vector<std::uint32_t> final_id(next, s);
    for (const auto& part : parts) {
      const std::size_t k = kKeep - 1 - part.second;
      if (k == pieces_.size()) continue;
      final_id[k] = static_cast<std::uint32_t>(segs_.size());
      Segment fresh;
      fresh.id = final_id[k];
      fresh.state = State::occupied;
      segs_.push_back(fresh);
    }
    for (std::size_t k = pieces_.size(); k < next; ++k)
      if (join[k]) final_id[k] = final_id[join[k] - 1];
    for (std::uint32_t v : members_) labels_[v] = final_id[kKeep - 1 - labels_[v]];
    recompute_statistics(s);
  }

  // Voxel count, mean occupancy, box and centroid of `s` and of the segments just appended, summed
  // in scan order.
  void recompute_statistics(std::uint32_t s) {
    struct Sum {
      std::uint64_t n = 0;
      double p = 0, c[3] = {0, 0, 0};
      std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u}, hi{0, 0, 0};
    };
    std::vector<Sum> sums(segs_.size());
    for (std::size_t m = 0; m < members_.size(); ++m) {
      Sum& t = sums[labels_[members_[m]]];
      ++t.n;
      t.p += g_.value(members_[m]);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t q = static_cast<std::uint32_t>(pts_[m][k]);
        t.c[k] += pts_[m][k];
        t.lo[k] = std::min(t.lo[k], q);
        t.hi[k] = std::max(t.hi[k], q);
      }
    }
    for (std::size_t id = 0; id < sums.size(); ++id) {
      const Sum& t = sums[id];
      if (id != s && t.n == 0) continue;
      Segment& seg = segs_[id];
      seg.voxels = t.n;
      seg.mop = t.p / double(t.n);
      seg.bbox_min = t.lo;
      seg.bbox_max = t.hi;
      for (int k = 0; k < 3; ++k) seg.centroid[k] = t.c[k] / double(t.n);
    }
  }

  const Grid& g_;
  const Dims d_;
  LabelArray& labels_;
  std::vector<Segment>& segs_;
  const kernels::PlanesKernels& k_;
  VoxelNeighbours neighbours_;
  Plane plane_;
  std::vector<std::uint32_t> members_, stack_;
  std::vector<Vec> pts_;
  std::vector<Piece> pieces_;
};

}  // namespace

void split_support_planes(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments,
                          std::size_t min_plane, bool occupied26, int threads, const kernels::Table& k) {
  if (min_plane == 0) return;
  // Candidates: occupied segments big enough for a plane and an object. Their voxels are found by
  // scanning each one's box, or, when the boxes add up to more than the map (sprawling segments
  // of a noisy map), bucketed in one pass over the labels. Buckets stay valid: a split only
  // relabels the voxels of the segment being split.
  const std::size_t original = segments.size();
  std::vector<std::uint32_t> candidates;
  std::size_t boxes = 0, voxels = 0;
  for (std::size_t s = 0; s < original; ++s) {
    const Segment& seg = segments[s];
    if (seg.state != State::occupied || seg.voxels < min_plane + kMinObjectVoxels) continue;
    if (seg.kind == Kind::structure) continue;  // rule 11's: its planes and objects are found
    // Temporary labels count down from the top of the id range; they must stay above every id.
    if (original + 2 * seg.voxels + 2 >= std::numeric_limits<std::uint32_t>::max()) continue;
    candidates.push_back(static_cast<std::uint32_t>(s));
    std::size_t box = 1;
    for (int k = 0; k < 3; ++k) box *= std::size_t(seg.bbox_max[k] - seg.bbox_min[k]) + 1;
    boxes += box;
    voxels += seg.voxels;
  }
  Splitter splitter(grid, labels, segments, occupied26, k.planes);
  std::vector<std::uint32_t> members;  // bucketed voxels of the candidates, candidate by candidate
  std::vector<std::size_t> start{0};
  if (boxes > labels.size()) {
    std::vector<std::uint32_t> slot(original, ~0u);
    for (std::uint32_t s : candidates) {
      slot[s] = static_cast<std::uint32_t>(start.size() - 1);
      start.push_back(start.back() + segments[s].voxels);
    }
    members.resize(voxels);
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < labels.size(); ++i) {
      const std::uint32_t k = slot[labels[i]];
      if (k != ~0u) members[fill[k]++] = static_cast<std::uint32_t>(i);
    }
  }
  const auto first = [&](std::size_t k) { return members.empty() ? nullptr : members.data() + start[k]; };
  const auto last = [&](std::size_t k) { return members.empty() ? nullptr : members.data() + start[k + 1]; };
  // The searches first (they only read), several segments at once on more threads (each
  // searching on one), or one segment's candidate planes over the threads; then the splits, one
  // segment after the other in candidate order, as before.
  std::vector<Splitter::Found> found(candidates.size());
  if (resolve_threads(threads) > 1 && candidates.size() > 1)
    parallel_for_dynamic(candidates.size(), threads, [&](std::size_t k0, std::size_t k1) {
      for (std::size_t k = k0; k < k1; ++k) found[k] = splitter.search(candidates[k], first(k), last(k), min_plane, 1);
    });
  else
    for (std::size_t k = 0; k < candidates.size(); ++k)
      found[k] = splitter.search(candidates[k], first(k), last(k), min_plane, threads);
  for (std::size_t k = 0; k < candidates.size(); ++k) splitter.split(candidates[k], first(k), last(k), found[k]);
}

}  // namespace occseg
