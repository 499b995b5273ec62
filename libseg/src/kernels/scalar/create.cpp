// The create kernels in plain C++ (kernels/create.hpp): the meaning of every create kernel.
#include "kernels/create_impl.hpp"
#include "stages/own_states.hpp"
#include "util/bit_rows.hpp"

namespace occseg::kernels::scalar {

void add_cells(const float* v, double* sums, std::size_t cells) {
  for (std::size_t k = 0; k < cells; ++k, v += 8) {  // eight additions each, in x order
    double acc = sums[k];
    acc += v[0], acc += v[1], acc += v[2], acc += v[3], acc += v[4], acc += v[5], acc += v[6], acc += v[7];
    sums[k] = acc;
  }
}

void own_states(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out) {
  detail::own_states_of(p, n, lo, hi, out);
}

void own_bits(const float* p, std::size_t n, float lo, float hi, word_t* u, word_t* o) {
  for (std::size_t i = 0; i < (n + 63) / 64; ++i) u[i] = o[i] = 0;
  for (std::size_t x = 0; x < n; ++x) {
    u[x / 64] |= static_cast<std::uint64_t>(!(p[x] < lo) && !(p[x] > hi)) << (x % 64);
    o[x / 64] |= static_cast<std::uint64_t>(p[x] > hi) << (x % 64);
  }
}

void pack_equal(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) {
  detail::pack_equal(bytes, n, v, bits);
}

}  // namespace occseg::kernels::scalar
