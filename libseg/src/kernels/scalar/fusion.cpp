// The scan fusion's ray walk in plain C++, one ray after the other: the meaning every other
// level's walk is tested against.
#include "kernels/fusion_levels.hpp"
#include "kernels/generic/fusion_walk.hpp"

namespace occseg::kernels::scalar {

namespace {

// One step of the walk (kernels/fusion.hpp); false when the walk is over.
bool step(Walk& w, std::uint8_t* marks) {
  mark_crossed(marks + w.i);
  if (w.i == w.end) {
    w.at_end = true;
    return false;
  }
  const int axis = w.tx[0] < w.ty[0] ? (w.tx[0] < w.tz[0] ? 0 : 2) : (w.ty[0] < w.tz[0] ? 1 : 2);
  if (axis == 0) {
    w.tx[0] += w.dx[0];
    w.i += w.sx;
    --w.rx;
  } else if (axis == 1) {
    w.ty[0] += w.dy[0];
    w.i += w.sy;
    --w.ry;
  } else {
    w.tz[0] += w.dz[0];
    w.i += w.sz;
    --w.rz;
  }
  if (w.rx < 0 || w.ry < 0 || w.rz < 0) return false;
  return --w.budget > 0;
}

}  // namespace

void fusion_walk_rays(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                      std::vector<std::uint64_t>& hits) {
  Walk w;
  while (next(w)) {
    while (step(w, marks)) {
    }
    finish_walk(w, dims, box, hits);
  }
}

}  // namespace occseg::kernels::scalar
