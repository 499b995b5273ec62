// Chooses the fusion stage's kernels for a level (kernels.hpp).
#include "kernels/fusion.hpp"

namespace occseg::kernels {

void select_fusion(FusionKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
