// Chooses the rules stage's kernels for a level (kernels.hpp).
#include "kernels/rules.hpp"

namespace occseg::kernels {

void select_rules(RulesKernels& k, Isa cap) {
  (void)k;
  (void)cap;
}

}  // namespace occseg::kernels
