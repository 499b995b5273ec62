// Chooses the create stage's kernels for a level (kernels.hpp).
#include "kernels/create.hpp"

namespace occseg::kernels {

void select_create(CreateKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
