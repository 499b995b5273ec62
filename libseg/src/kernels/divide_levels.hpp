// The division's kernels of each instruction set (internal to kernels/), defined in
// scalar/divide.cpp, sse2/, avx2/ and avx512/, for select_divide.cpp to put in the table.
// Each has the contract of its slot in kernels/divide.hpp.
#pragma once
#include "kernels/divide.hpp"

namespace occseg::kernels {

namespace scalar {
void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h);
std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out);
std::uint64_t total(const std::uint32_t* h, std::size_t n);
void sum_eight(std::uint32_t* h, const std::uint32_t* a, std::size_t stride, std::size_t n);
void add_counts(std::uint32_t* h, const std::uint32_t* a, std::size_t n);
}  // namespace scalar

namespace sse2 {
// Rows tested eight (two rows: sixteen) codes at a time for "all equal".
void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h);
std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out);
}  // namespace sse2

namespace avx2 {
// The codes other than the hinted ones packed to a list by a byte shuffle (POPCNT too).
void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h);
std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out);
std::uint64_t total(const std::uint32_t* h, std::size_t n);
void sum_eight(std::uint32_t* h, const std::uint32_t* a, std::size_t stride, std::size_t n);
void add_counts(std::uint32_t* h, const std::uint32_t* a, std::size_t n);
}  // namespace avx2

namespace avx512 {
// The codes other than the hinted ones packed by a 16-bit compress: needs AVX-512 VBMI2.
void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h);
// A 32-bit compress (AVX-512 F).
std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out);
}  // namespace avx512

}  // namespace occseg::kernels
