// Chooses the label stage's kernels for a level (kernels.hpp).
#include "kernels/label.hpp"

namespace occseg::kernels {

void select_label(LabelKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
