// Support planes: splits an occupied segment into the plane it mostly lies on (a table top, a
// floor) and the objects standing on that plane's observed side (docs/algorithm.md, default
// preset rule 5). Touching objects of one state are one connected region, so labelling alone can
// never separate a mug from the table it stands on.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "stages/label.hpp"

namespace occseg {

// Inliers are voxels whose centre lies within this distance (voxel edges) of the plane: half the
// thickness of a 26-connected digital plane (sqrt(3)/2), so the layer of an object resting on an
// axis-aligned plane, one voxel away, is never an inlier.
constexpr double kPlaneInlierDistance = 0.866;
// Pieces smaller than this (a 3 x 3 x 3 cube), or rising less than kMinObjectHeight voxel edges
// above the plane, are the plane's own noise (a range sensor's surface is a few voxels thick) and
// stay with it.
constexpr std::size_t kMinObjectVoxels = 27;
constexpr double kMinObjectHeight = 3.0;
// ... and rising less than this many times the robust spread (sigma) of the plane's surface.
constexpr double kNoiseHeights = 5.0;

// A plane n . x = d in voxel-index coordinates (voxel centres at integer x, y, z), |n| = 1.
struct Plane {
  std::array<double, 3> n{0, 0, 1};
  double d = 0;
  double distance(double x, double y, double z) const { return n[0] * x + n[1] * y + n[2] * z - d; }
};

// The plane that most of `points` lie on: deterministic MSAC (RANSAC scoring squared distances
// capped at kPlaneInlierDistance) over at most 4096 of them (the generator is seeded with `seed`),
// refined by least-squares fits to the inliers. `inliers` receives how many of all points are
// within kPlaneInlierDistance of the result. Returns false for fewer than 3 points or when all
// are collinear. Candidate planes are scored on up to `threads` threads (0: all cores) with the
// kernels `k`; the result never depends on the thread count or the kernels. With `axis` 0, 1 or 2
// only planes whose drawn normal lies within 45 degrees of that axis are candidates (the refits may
// tilt it further); -1: any. `positions`, when given, receives the positions in `points` of the
// result's inliers, ascending (empty when it returns false).
bool fit_dominant_plane(const std::vector<std::array<double, 3>>& points, std::uint64_t seed, Plane& plane,
                        std::size_t& inliers, int threads = 1, const kernels::Table& k = kernels::active(),
                        int axis = -1, std::vector<std::uint32_t>* positions = nullptr);
// The same over points given by coordinate (point i is (x[i], y[i], z[i])): the same result bit
// for bit, without a copy of them.
bool fit_dominant_plane(const kernels::PlanePoints& points, std::uint64_t seed, Plane& plane, std::size_t& inliers,
                        int threads, const kernels::Table& k, int axis, std::vector<std::uint32_t>* positions);

// Splits every occupied segment (not already `structure`: rule 11, rules/structure.hpp, split it
// at several planes) with at least `min_plane` voxels whose dominant plane holds at
// least `min_plane` of them and at least half of them. Pieces of the rest (connected as
// `occupied26` says) that lie on the plane's open side (the side its voxels see free space on),
// have at least kMinObjectVoxels voxels and rise at least max(kMinObjectHeight, kNoiseHeights x
// sigma) above it (sigma: the robust spread of the surface along the normal) become new segments,
// numbered after all existing ones in the order of their first voxel. Everything else (the
// plane, pieces on its far side such as a table's legs, small or low pieces) stays in the
// segment, whose first component keeps its id (further components get new ids too, or join the
// object they touch when smaller than kMinObjectVoxels). A segment whose best plane holds under
// 40 % of a 4096-voxel sample is dropped before its voxels are listed. Statistics of changed
// segments are recomputed. The plane searches run first, several segments at once on up to
// `threads` threads (0: all cores; or one segment's candidate planes over them when it is the
// only one), then the splits one segment after the other; results never depend on the thread
// count or the kernels `k`.
void split_support_planes(const Grid& grid, LabelArray& labels, std::vector<Segment>& segments,
                          std::size_t min_plane, bool occupied26, int threads = 1,
                          const kernels::Table& k = kernels::active());

namespace detail {
// The MSAC cost of `plane` on `points` as the plane search computes it with the kernels `k`: the
// squared distances, capped at kPlaneInlierDistance^2, point i's added to lane i % 4 in point
// order, the cost (l0 + l1) + (l2 + l3). For tests.
double msac_cost(const std::vector<std::array<double, 3>>& points, const Plane& plane,
                 const kernels::Table& k = kernels::active());
// msac_cost() of two planes as the search scores them, side by side: each must be msac_cost()'s
// bit for bit, or, once its sum reaches `stop`, some sum at or above `stop`. For tests.
void msac_cost_pair(const std::vector<std::array<double, 3>>& points, const Plane& a, const Plane& b, double stop,
                    double& cost_a, double& cost_b, const kernels::Table& k = kernels::active());
}  // namespace detail

}  // namespace occseg
