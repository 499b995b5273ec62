// The support planes' kernels (kernels.hpp): the slots, and how a table fills them. Each slot is
// a whole loop over a plane search's sample or a row of labels; rules/planes.cpp holds the rule.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"

namespace occseg::kernels {

// The sample of a plane search by coordinate: point i is (x[i], y[i], z[i]), i < n.
struct PlanePoints {
  const double* x;
  const double* y;
  const double* z;
  std::size_t n;
};

// A plane n . p = d; point p's distance to it is ((n0 * x + n1 * y) + n2 * z) - d, in that order.
struct MsacPlane {
  double n0, n1, n2, d;
};

// Points between two looks of a cost at its bound (a multiple of 4).
constexpr std::size_t kMsacChunk = 256;

struct PlanesKernels {
  // The MSAC cost of `pl` on `pts`: point i's term min(e * e, cap) (e: its distance, computed as
  // MsacPlane says, without FMA) is added to lane i % 4, each lane in point order from 0.0, and the
  // cost is (l0 + l1) + (l2 + l3). A cost below `stop` is returned bit for bit; one that reaches
  // it may be cut short: then some sum of its lanes so far at or above `stop` is returned (terms
  // are not negative: the cost could only grow). The kernels look at the bound after every
  // kMsacChunk points.
  double (*cost)(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop);
  // cost() of two planes, each result as cost() says.
  void (*cost_pair)(const PlanePoints& pts, const MsacPlane& a, const MsacPlane& b, double cap, double stop,
                    double& cost_a, double& cost_b);
  // cost() that also lists the positions i of the points with |e| <= `inlier` (e as cost()
  // computes it), ascending, into out[0 ..) (room for pts.n), their number into `count`: one pass
  // for a refit's cost and its inliers. The list and count are complete when the cost returned is
  // below `stop`; else they are unspecified (out[0 .. pts.n) may have been written).
  double (*cost_inliers)(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop, double inlier,
                         std::uint32_t* out, std::size_t& count);
  // Which of the labels row[x0 .. x1) equal s (x0 < x1): bit k % 64 of bits[k / 64] for
  // row[x0 + k], the bits past x1 - x0 clear (the words past the last one untouched). Returns how
  // many.
  std::size_t (*row_members)(const std::uint32_t* row, std::size_t x0, std::size_t x1, std::uint32_t s,
                             std::uint64_t* bits);
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_planes(PlanesKernels& k, Isa cap);

}  // namespace occseg::kernels
