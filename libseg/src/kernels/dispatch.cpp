// The one processor probe and the tables built from it (kernels.hpp).
#include <array>

#include "kernels/cpu_features.hpp"
#include "kernels/kernels.hpp"

namespace occseg::kernels {

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::scalar: return "scalar";
    case Isa::sse2: return "sse2";
    case Isa::avx2: return "avx2";
    case Isa::avx512: return "avx512";
    case Isa::avx512vbmi: return "avx512vbmi";
  }
  return "?";
}

bool cpu_has(Isa isa) {
  switch (isa) {
    case Isa::scalar: return true;
#if defined(__SSE2__)
    case Isa::sse2: return true;
#else
    case Isa::sse2: return false;
#endif
    case Isa::avx2: return cpu_has_avx2();
    case Isa::avx512: return cpu_has_avx512();
    case Isa::avx512vbmi: return cpu_has_avx512vbmi() && cpu_has_avx512vbmi2();
  }
  return false;
}

Isa best_isa() {
  static const Isa best = [] {
    Isa b = Isa::scalar;
    for (Isa l : kIsaLevels)
      if (cpu_has(l)) b = l;
    return b;
  }();
  return best;
}

namespace {

Table build(Isa cap) {
  // A level the processor lacks gives the table of the highest one below it that it has.
  while (cap != Isa::scalar && !cpu_has(cap)) cap = static_cast<Isa>(static_cast<int>(cap) - 1);
  Table t;
  t.isa = cap;
  select_texture(t.texture, cap);
  select_divide(t.divide, cap);
  select_create(t.create, cap);
  select_refine(t.refine, cap);
  select_rules(t.rules, cap);
  select_label(t.label, cap);
  select_planes(t.planes, cap);
  select_fusion(t.fusion, cap);
  return t;
}

thread_local const Table* t_scoped = nullptr;

}  // namespace

const Table& table(Isa cap) {
  static const std::array<Table, 5> tables = {build(Isa::scalar), build(Isa::sse2), build(Isa::avx2),
                                              build(Isa::avx512), build(Isa::avx512vbmi)};
  return tables[static_cast<int>(cap)];
}

const Table& active() { return t_scoped ? *t_scoped : table(best_isa()); }

ScopedIsa::ScopedIsa(Isa cap) : previous_(t_scoped) { t_scoped = &table(cap); }
ScopedIsa::~ScopedIsa() { t_scoped = previous_; }

}  // namespace occseg::kernels
