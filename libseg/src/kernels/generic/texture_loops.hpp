// The texture kernels' plain loops (internal to kernels/): compiled as they are for the scalar
// table, and inlined into functions compiled for AVX2 for the AVX2 table (the compiler
// vectorises them for each). Internal linkage and always inlined, so no copy compiled for one
// instruction set can stand in for another's.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "kernels/texture.hpp"

namespace occseg::kernels::generic {

// True when every p[0, n) lies in [0, 1] (a NaN does not). Counts instead of stopping at the
// first bad value, so that it vectorises.
static inline __attribute__((always_inline)) bool values_in_range(const float* p, std::size_t n) {
  std::size_t bad = 0;
  for (std::size_t i = 0; i < n; ++i) bad += !((p[i] >= 0.0f) & (p[i] <= 1.0f));
  return bad == 0;
}

// Parked steps (kRecheckStep where uncertain) of n consecutive voxels whose neighbours are those
// of `Present`. texture_unit()'s arithmetic is in double; this loop runs in float, which is
// exact for the comparisons (floats compare the same in double) and within 1e-6 of the double
// contrast: each mean of at most six floats in [0, 1] has a float error below
// 6 * 2^-24 * mean < 3.6e-7, the difference below 7.8e-7. A voxel gets its step from the float
// value only when the whole interval c +- 1e-6 lies in one step (and above 0); otherwise it is
// marked kRecheckStep and recomputed in double by the stage, so the steps are exactly those of
// texture_unit().
//
// With Clamp the loop is defined for any float (a NaN or an infinity among the values: the tails
// of the vector kernels, whose rows are checked as they are computed, not before): the float
// steps are clamped into [-1, kTop] before the conversion, which changes no valid voxel's step.
// Without it (rows whose values were checked before) the loop vectorises; GCC leaves the clamped
// one scalar.
template <unsigned Present, bool Clamp = false>
static inline __attribute__((always_inline)) void contrast_row(const float* p, const std::ptrdiff_t* off, std::size_t n, code_t* out) {
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};
  constexpr float kErr = 1e-6f, kFine = ContrastQuantizer::kFine;
  constexpr int kTop = ContrastQuantizer::kFine - 1;
  for (std::size_t x = 0; x < n; ++x) {
    const float c = p[x];
    float s1 = 0, s0 = 0, n1 = 0, n0 = 0;
    // Neighbour K's part, in neighbour order (unrolled: K is a constant).
    const auto neighbour = [&](auto K) {
      if constexpr ((Present & (1u << K)) != 0) {
        const float v = p[std::ptrdiff_t(x) + o[K]];
        const bool up = v >= c;
        s1 += up ? v : 0.0f;
        s0 += up ? 0.0f : v;
        n1 += up ? 1.0f : 0.0f;
        n0 += up ? 0.0f : 1.0f;
      }
    };
    neighbour(std::integral_constant<int, 0>{}), neighbour(std::integral_constant<int, 1>{});
    neighbour(std::integral_constant<int, 2>{}), neighbour(std::integral_constant<int, 3>{});
    neighbour(std::integral_constant<int, 4>{}), neighbour(std::integral_constant<int, 5>{});
    const float con = s1 / (n1 > 0 ? n1 : 1.0f) - s0 / (n0 > 0 ? n0 : 1.0f);
    const bool two_sided = (n1 > 0) & (n0 > 0);
    float lo = (con - kErr) * kFine, hi = (con + kErr) * kFine;  // |con| <= 1 for a valid map
    if constexpr (Clamp) {  // std::max(-1, v) is -1 for a NaN v
      lo = std::min(std::max(-1.0f, lo), float(kTop));
      hi = std::min(std::max(-1.0f, hi), float(kTop));
    }
    int step = static_cast<int>(lo), step_hi = static_cast<int>(hi);
    step = step < kTop ? step : kTop;
    step_hi = step_hi < kTop ? step_hi : kTop;
    const bool sure = (lo > 0.0f) & (step == step_hi);
    const int v = sure ? step + 1 : int(kRecheckStep);
    out[x] = static_cast<std::uint16_t>(two_sided ? v : 0);
  }
}

// LBP codes of n consecutive voxels whose neighbours are those of `Present`.
template <unsigned Present>
static inline __attribute__((always_inline)) void lbp_row(const float* p, const std::ptrdiff_t* off, std::size_t n, std::uint8_t* out) {
  const std::ptrdiff_t o[6] = {off[0], off[1], off[2], off[3], off[4], off[5]};
  for (std::size_t x = 0; x < n; ++x) {
    const float c = p[x];
    std::uint8_t l = 0;
    const auto bit = [&](auto K) {  // neighbour K's bit (unrolled: K is a constant)
      if constexpr ((Present & (1u << K)) != 0)
        l |= p[std::ptrdiff_t(x) + o[K]] >= c ? std::uint8_t(1u << K) : std::uint8_t(0);
    };
    bit(std::integral_constant<int, 0>{}), bit(std::integral_constant<int, 1>{}), bit(std::integral_constant<int, 2>{});
    bit(std::integral_constant<int, 3>{}), bit(std::integral_constant<int, 4>{}), bit(std::integral_constant<int, 5>{});
    out[x] = l;
  }
}

// True when some v[x] is kRecheckStep (branch-free, so it vectorises: rechecks are rare).
static inline __attribute__((always_inline)) bool any_recheck(const code_t* v, std::size_t n) {
  unsigned any = 0;
  for (std::size_t x = 0; x < n; ++x) any |= v[x] == kRecheckStep;
  return any != 0;
}

// Adds the steps list[0, len) to the four interleaved histograms, one step to each in turn.
static inline __attribute__((always_inline)) void count_list(const std::uint16_t* list, std::size_t len, std::uint64_t* h) {
  static_assert(kStepHistograms == 4, "four histograms, one per voxel of a group");
  std::size_t i = 0;
  for (; i + 4 <= len; i += 4) {
    ++h[list[i]];
    ++h[kStepStride + list[i + 1]];
    ++h[2 * kStepStride + list[i + 2]];
    ++h[3 * kStepStride + list[i + 3]];
  }
  for (; i < len; ++i) ++h[list[i]];
}

// lvl[x] = (v[x] != 0) + #{k : v[x] > rises[k]}.
static inline __attribute__((always_inline)) void levels_row(const code_t* __restrict v, std::size_t n, const std::uint16_t* rises, std::size_t nr,
                            std::uint16_t* __restrict lvl) {
  for (std::size_t x = 0; x < n; ++x) lvl[x] = v[x] != 0;
  for (std::size_t k = 0; k < nr; ++k) {
    const std::uint16_t t = rises[k];
    for (std::size_t x = 0; x < n; ++x) lvl[x] = static_cast<std::uint16_t>(lvl[x] + (v[x] > t));
  }
}

// code[x] = lbp[x] * bins + lvl[x].
static inline __attribute__((always_inline)) void combine_row(const std::uint8_t* __restrict lbp, const std::uint16_t* __restrict lvl, std::size_t n,
                             std::uint16_t bins, code_t* __restrict code) {
  for (std::size_t x = 0; x < n; ++x) code[x] = static_cast<std::uint16_t>(lbp[x] * bins + lvl[x]);
}

}  // namespace occseg::kernels::generic
