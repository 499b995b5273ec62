// The create stage's kernels (kernels.hpp): the slots, and how a table fills them. Each slot is
// a loop over one row of the map (or a run of it).
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"
#include "util/aliasing.hpp"

namespace occseg::kernels {

using detail::word_t;

struct CreateKernels {
  // sums[k] += v[8k] + v[8k + 1] + ... + v[8k + 7] for k in [0, cells): the sums of whole cells
  // of 8 voxels along a row, each sum's additions in x order (acc += v[0], then v[1], ...) in
  // double, so every kernel gives the same sums bit for bit.
  void (*add_cells)(const float* v, double* sums, std::size_t cells) = nullptr;
  // out[i] = own state of p[i] for i in [0, n) (stages/own_states.hpp's own_states_of).
  void (*own_states)(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out) = nullptr;
  // The own states of p[0, n) as bit rows (bit_rows.hpp's layout, bits past n 0, the words
  // written whole): u where lo <= p <= hi (unknown; NaN too, as in own_states), o where p > hi.
  void (*own_bits)(const float* p, std::size_t n, float lo, float hi, word_t* u, word_t* o) = nullptr;
  // The bit row of bytes[0, n) == v (util/bit_rows.hpp's pack_equal).
  void (*pack_equal)(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits) = nullptr;
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_create(CreateKernels& k, Isa cap);

}  // namespace occseg::kernels
