// Chooses the support planes' kernels for a level (kernels.hpp).
#include "kernels/cpu_features.hpp"
#include "kernels/planes_levels.hpp"

namespace occseg::kernels {

void select_planes(PlanesKernels& k, Isa cap) {
  k.cost = scalar::planes_cost;
  k.cost_pair = scalar::planes_cost_pair;
  k.cost_inliers = scalar::planes_cost_inliers;
  k.row_members = scalar::planes_row_members;
#if defined(__x86_64__) && defined(__GNUC__)
  if (cap >= Isa::avx2 && cpu_has_avx2()) {
    k.cost = avx2::planes_cost;
    k.cost_pair = avx2::planes_cost_pair;
    k.cost_inliers = avx2::planes_cost_inliers;
    k.row_members = avx2::planes_row_members;
  }
#endif
}

}  // namespace occseg::kernels
