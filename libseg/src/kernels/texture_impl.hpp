// The texture kernels of each instruction set (internal to kernels/): what select_texture()
// puts in the slots of TextureKernels (kernels/texture.hpp, where each slot's contract is).
#pragma once
#include "kernels/texture.hpp"

namespace occseg::kernels {

namespace scalar {
bool values_in_range(const float* p, std::size_t n);
bool contrast_row(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* steps, std::uint8_t* lbp,
                  bool& maybe_recheck);
void contrast_row_any(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present, code_t* steps,
                      std::uint8_t* lbp);
bool any_recheck(const code_t* steps, std::size_t n);
void count_steps(const code_t* steps, std::size_t n, std::uint64_t* h, std::uint16_t* list);
void codes_from_lbp(code_t* row, const std::uint8_t* lbp, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                    std::uint16_t bins);
std::size_t codes_row(const float* p, const std::ptrdiff_t* off, std::size_t n, const std::uint16_t* rises,
                      std::size_t nr, std::uint16_t bins, code_t* row);
void lbp_row(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present, std::uint8_t* out);
void levels_row(const code_t* v, std::size_t n, const std::uint16_t* rises, std::size_t nr, std::uint16_t* lvl);
void combine_row(const std::uint8_t* lbp, const std::uint16_t* lvl, std::size_t n, std::uint16_t bins, code_t* code);
}  // namespace scalar

#if defined(__x86_64__) && defined(__GNUC__)
namespace avx2 {
bool values_in_range(const float* p, std::size_t n);
bool contrast_row(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* steps, std::uint8_t* lbp,
                  bool& maybe_recheck);
bool any_recheck(const code_t* steps, std::size_t n);
void count_steps(const code_t* steps, std::size_t n, std::uint64_t* h, std::uint16_t* list);
void codes_from_lbp(code_t* row, const std::uint8_t* lbp, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                    std::uint16_t bins);
std::size_t codes_row(const float* p, const std::ptrdiff_t* off, std::size_t n, const std::uint16_t* rises,
                      std::size_t nr, std::uint16_t bins, code_t* row);
void lbp_row(const float* p, const std::ptrdiff_t* off, std::size_t n, unsigned present, std::uint8_t* out);
void levels_row(const code_t* v, std::size_t n, const std::uint16_t* rises, std::size_t nr, std::uint16_t* lvl);
void combine_row(const std::uint8_t* lbp, const std::uint16_t* lvl, std::size_t n, std::uint16_t bins, code_t* code);
}  // namespace avx2

namespace avx512 {
// AVX-512 F, BW and VL; contrast_row_vbmi also looks a count up by a byte permute (VBMI), and
// count_steps packs with a 16-bit compress (VBMI2): each only where the processor has it.
bool contrast_row(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* steps, std::uint8_t* lbp,
                  bool& maybe_recheck);
bool contrast_row_vbmi(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* steps, std::uint8_t* lbp,
                       bool& maybe_recheck);
void count_steps(const code_t* steps, std::size_t n, std::uint64_t* h, std::uint16_t* list);
void codes_from_lbp(code_t* row, const std::uint8_t* lbp, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                    std::uint16_t bins);
}  // namespace avx512
#endif

}  // namespace occseg::kernels
