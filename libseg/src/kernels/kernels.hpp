// The kernel table: one function pointer per hand-vectorised loop of the pipeline, per stage.
// A call picks its table once (active(), on the calling thread) and hands it to every stage it
// runs; worker threads use the table they were given, never active() (which is per thread).
#pragma once
#include "kernels/create.hpp"
#include "kernels/divide.hpp"
#include "kernels/fusion.hpp"
#include "kernels/isa.hpp"
#include "kernels/label.hpp"
#include "kernels/planes.hpp"
#include "kernels/refine.hpp"
#include "kernels/rules.hpp"
#include "kernels/texture.hpp"

namespace occseg::kernels {

struct Table {
  Isa isa = Isa::scalar;  // the level the table was built for (capped by the processor)
  TextureKernels texture;
  DivideKernels divide;
  CreateKernels create;
  RefineKernels refine;
  RulesKernels rules;
  LabelKernels label;
  PlanesKernels planes;
  FusionKernels fusion;
};

// The table for `cap` (built once per level, kept for the life of the process).
const Table& table(Isa cap);

// The table a call made on this thread uses: the innermost ScopedIsa's, else table(best_isa()).
const Table& active();

// Caps the kernels of calls made on this thread for the object's lifetime (tests, benchmarks).
// Scopes nest; the previous cap comes back however the scope is left.
class ScopedIsa {
 public:
  explicit ScopedIsa(Isa cap);
  ~ScopedIsa();
  ScopedIsa(const ScopedIsa&) = delete;
  ScopedIsa& operator=(const ScopedIsa&) = delete;

 private:
  const Table* previous_;
};

}  // namespace occseg::kernels
