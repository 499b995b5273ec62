// Chooses the planes stage's kernels for a level (kernels.hpp).
#include "kernels/planes.hpp"

namespace occseg::kernels {

void select_planes(PlanesKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
