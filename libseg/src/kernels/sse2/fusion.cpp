// The scan fusion's SSE2 ray walk (every x86-64 has SSE2): four rays at a time, one step of each
// in turn. Each step depends on the previous one (compare tmax, add tdelta: about 9 cycles of
// latency for a few instructions), so the processor overlaps the four rays' chains.
#include "kernels/fusion_levels.hpp"

#if defined(__SSE2__)
#include "kernels/sse2/fusion_step.hpp"

namespace occseg::kernels::sse2 {

void fusion_walk_rays(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                      std::vector<std::uint64_t>& hits) {
  constexpr int kLanes = 4;
  Walk lanes[kLanes];
  bool busy[kLanes] = {};
  int active = 0;
  for (int k = 0; k < kLanes; ++k) active += busy[k] = next(lanes[k]);
  while (active == kLanes) {
    for (int k = 0; k < kLanes; ++k)
      if (!sse2_step(lanes[k], marks)) {
        finish_walk(lanes[k], dims, box, hits);
        if (!next(lanes[k])) {
          busy[k] = false;
          --active;
        }
      }
  }
  for (int k = 0; k < kLanes; ++k)  // the last few walks, one by one
    if (busy[k]) {
      while (sse2_step(lanes[k], marks)) {
      }
      finish_walk(lanes[k], dims, box, hits);
    }
}

}  // namespace occseg::kernels::sse2

#endif
