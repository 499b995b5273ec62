// The create kernels of each instruction set (internal to kernels/): what select_create() puts
// in the slots of CreateKernels (kernels/create.hpp, where each slot's contract is).
#pragma once
#include "kernels/create.hpp"

namespace occseg::kernels {

namespace scalar {
void add_cells(const float* v, double* sums, std::size_t cells);
void own_states(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out);
void own_bits(const float* p, std::size_t n, float lo, float hi, word_t* u, word_t* o);
void pack_equal(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits);
}  // namespace scalar

#if defined(__x86_64__) && defined(__GNUC__)
namespace sse2 {
void own_states(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out);
void pack_equal(const std::uint8_t* bytes, std::size_t n, std::uint8_t v, word_t* bits);
}  // namespace sse2

namespace avx2 {
void add_cells(const float* v, double* sums, std::size_t cells);
void own_states(const float* p, std::size_t n, float lo, float hi, std::uint8_t* out);
void own_bits(const float* p, std::size_t n, float lo, float hi, word_t* u, word_t* o);
}  // namespace avx2

namespace avx512 {  // AVX-512 F
void add_cells(const float* v, double* sums, std::size_t cells);
void own_bits(const float* p, std::size_t n, float lo, float hi, word_t* u, word_t* o);
}  // namespace avx512
#endif

}  // namespace occseg::kernels
