// Chooses the refine stage's kernels for a level (kernels.hpp).
#include "kernels/refine.hpp"

namespace occseg::kernels {

void select_refine(RefineKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
