// Tests over every instruction-set level of the kernels (kernels/isa.hpp): a parameterised
// fixture that caps the kernels for the test's own scope and skips, saying so, a level the
// processor lacks; and a loop for tests that compare levels inside one test.
#pragma once
#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "kernels/kernels.hpp"

namespace occseg::testing_isa {

class IsaTest : public ::testing::TestWithParam<kernels::Isa> {
 protected:
  void SetUp() override {
    if (!kernels::cpu_has(GetParam())) GTEST_SKIP() << "this processor has no " << kernels::isa_name(GetParam());
    scope_.emplace(GetParam());
  }
  void TearDown() override { scope_.reset(); }

 private:
  std::optional<kernels::ScopedIsa> scope_;
};

inline std::string isa_test_name(const ::testing::TestParamInfo<kernels::Isa>& info) {
  return kernels::isa_name(info.param);
}

// Calls body(level) once per level the processor has, with the kernels capped there; a missing
// level is reported on the test's output. Returns the number of levels run.
template <class Body>
int for_each_isa(Body&& body) {
  int ran = 0;
  for (kernels::Isa level : kernels::kIsaLevels) {
    if (!kernels::cpu_has(level)) {
      std::printf("[   INFO   ] kernels at level %s not run: this processor lacks it\n", kernels::isa_name(level));
      continue;
    }
    SCOPED_TRACE(std::string("kernels: ") + kernels::isa_name(level));
    kernels::ScopedIsa scope(level);
    body(level);
    ++ran;
  }
  return ran;
}

}  // namespace occseg::testing_isa

// Instantiates a suite derived from IsaTest at every level.
#define OCCSEG_INSTANTIATE_ISA_LEVELS(Suite)                                                      \
  INSTANTIATE_TEST_SUITE_P(Isa, Suite, ::testing::ValuesIn(::occseg::kernels::kIsaLevels), \
                           ::occseg::testing_isa::isa_test_name)
