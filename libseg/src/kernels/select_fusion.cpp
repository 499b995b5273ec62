// Chooses the scan fusion's kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/fusion_levels.hpp"

namespace occseg::kernels {

void select_fusion(FusionKernels& k, Isa cap) {
  k.walk_rays = scalar::fusion_walk_rays;
#if defined(__SSE2__)
  if (cap >= Isa::sse2) k.walk_rays = sse2::fusion_walk_rays;
#endif
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx2 && cpu_has_avx2()) k.walk_rays = avx2::fusion_walk_rays;
#endif
}

}  // namespace occseg::kernels
