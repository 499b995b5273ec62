// The rules stage's kernels (kernels.hpp): the slots, and how a table fills them.
#pragma once
#include "kernels/isa.hpp"

namespace occseg::kernels {

struct RulesKernels {
  int unused = 0;  // placeholder until the stage's loops move here
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_rules(RulesKernels& k, Isa cap);

}  // namespace occseg::kernels
