// The labelling's kernels of every level (select_label.cpp fills the table with them).
#pragma once
#include <cstddef>
#include <cstdint>

namespace occseg::kernels {

namespace scalar {
void label_row_starts(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits, std::size_t i0);
std::size_t label_count_runs(const std::uint8_t* s, std::size_t rows, std::size_t nx, std::size_t every);
double label_run_sum(const float* v, std::size_t n);
}  // namespace scalar

#if defined(__SSE2__)
namespace sse2 {
void label_row_starts(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits, std::size_t i0);
std::size_t label_count_runs(const std::uint8_t* s, std::size_t rows, std::size_t nx, std::size_t every);
double label_run_sum(const float* v, std::size_t n);
}  // namespace sse2
#endif

#if defined(__x86_64__) && defined(__GNUC__)
namespace avx2 {
void label_row_starts(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits, std::size_t i0);
}  // namespace avx2

namespace avx512 {
double label_run_sum(const float* v, std::size_t n);
}  // namespace avx512
#endif

}  // namespace occseg::kernels
