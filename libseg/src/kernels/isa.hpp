// Instruction-set levels of the kernels, and what the processor running this has.
#pragma once

namespace occseg::kernels {

// Levels in the order each adds to the one before. A table of kernels built for a level uses,
// in every slot, the fastest kernel at or below that level that the processor has.
//   scalar      plain C++, the meaning of every kernel; every other kernel is tested against it
//   sse2        the x86-64 baseline (SSE2 kernels where one exists, else the scalar one)
//   avx2        AVX2 (with POPCNT where a kernel counts bits)
//   avx512      AVX-512 F, BW and VL
//   avx512vbmi  AVX-512 VBMI and VBMI2 (byte permutes, 16-bit compress) where a kernel uses them
enum class Isa : int { scalar = 0, sse2 = 1, avx2 = 2, avx512 = 3, avx512vbmi = 4 };
constexpr Isa kIsaLevels[] = {Isa::scalar, Isa::sse2, Isa::avx2, Isa::avx512, Isa::avx512vbmi};

const char* isa_name(Isa isa);
// True when the processor (and the system, which must save the registers) supports the level.
bool cpu_has(Isa isa);
// The highest level cpu_has (asked once per process).
Isa best_isa();

}  // namespace occseg::kernels
