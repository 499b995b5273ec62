// Chooses the divide stage's kernels for a level (kernels.hpp).
#include "kernels/divide.hpp"

namespace occseg::kernels {

void select_divide(DivideKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
