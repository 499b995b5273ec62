// The default rules' kernels in plain C++ (kernels/rules.hpp): the meaning of every slot.
#include "kernels/generic/rules_loops.hpp"

namespace occseg::kernels::scalar {

void rules_row(std::uint8_t* st, const word_t* u, const word_t* o, const word_t* reg, const word_t* t, std::size_t n,
               std::size_t first, std::vector<std::size_t>& seeds, word_t* f, word_t* un, word_t* oc) {
  generic::rules_row(st, u, o, reg, t, n, first, seeds, f, un, oc);
}

void unpack_half(const word_t* bits, const std::uint8_t* own, std::size_t nx, std::uint8_t* out) {
  for (std::size_t x = 0; x < nx; ++x)
    out[x] = static_cast<std::uint8_t>(((bits[x / 64] >> (x % 64)) & 1) & (own[x] == rules::kUnknown));
}

}  // namespace occseg::kernels::scalar
