// The scan fusion's kernels (kernels.hpp): the ray walk's state, and the slot that walks a block
// of rays. mapping/fusion.cpp sets each walk up and applies the marks.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "kernels/isa.hpp"
#include "occseg/grid.hpp"

namespace occseg::kernels {

// Voxels a scan may have marked: per axis, the range between the first and the last cell of
// every walk (walks are monotone along each axis). The apply pass only visits this box.
struct TouchBox {
  long lo[3] = {std::numeric_limits<long>::max(), std::numeric_limits<long>::max(),
                std::numeric_limits<long>::max()};
  long hi[3] = {-1, -1, -1};
  void add(const long* c) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], c[k]);
      hi[k] = std::max(hi[k], c[k]);
    }
  }
  void merge(const TouchBox& o) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], o.lo[k]);
      hi[k] = std::max(hi[k], o.hi[k]);
    }
  }
  bool empty() const { return hi[0] < lo[0]; }
};

// One Amanatides & Woo voxel traversal in progress. A step marks the current voxel crossed; the
// walk is over on its end voxel, after `budget` steps, or when a step would leave the grid (a
// room counter turns negative). Otherwise it moves along the axis of the smallest tmax
// (tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? x : z) : (tmax[1] < tmax[2] ? y : z)), adding that
// axis's tdelta to its tmax, its stride to i and -1 to its room.
struct Walk {
  // tmax and tdelta per axis in element 0. Element 1 is 0: the SSE2 walk loads each pair as one
  // register, whose high lane it never uses.
  alignas(16) double tx[2], ty[2], tz[2], dx[2], dy[2], dz[2];
  std::uint64_t i, end, sx, sy, sz;  // voxel index, end voxel index, index strides of one step
  long rx, ry, rz, budget;           // steps left along each axis inside the grid; steps left
  long c0[3], room[3], step[3];      // start voxel, initial room, step signs (for the touched box)
  bool hit;                          // the end voxel holds a return (else it is only crossed)
  bool at_end;                       // the walk stopped on its end voxel (set when it is over)
};

// The rays of a block, one at a time: next(w) sets up the next ray's walk in w and returns true,
// or returns false when none is left. (A reference to the caller's function object.)
class NextRay {
 public:
  template <class F>
  explicit NextRay(F& f) : obj_(&f), call_([](void* o, Walk& w) -> bool { return (*static_cast<F*>(o))(w); }) {}
  bool operator()(Walk& w) const { return call_(obj_, w); }

 private:
  void* obj_;
  bool (*call_)(void*, Walk&);
};

struct FusionKernels {
  // Walks every ray `next` gives to its end. Crossed voxels get mark 1 (a relaxed atomic load
  // and, on an unmarked voxel, a relaxed atomic store, so that several threads may walk into the
  // same marks); `box` grows by every voxel a walk covered; the end voxel of each walk that
  // reached it holding a return (Walk::hit) is appended to `hits`. The marks, the box and the set
  // of hits never depend on the level (the order of the hits may).
  void (*walk_rays)(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                    std::vector<std::uint64_t>& hits);
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_fusion(FusionKernels& k, Isa cap);

}  // namespace occseg::kernels
