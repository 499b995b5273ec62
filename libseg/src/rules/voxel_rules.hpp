// The default preset's three per-voxel rules on one voxel (docs/algorithm.md, "Presets", rules 1-3):
// their one statement. kernels/scalar/rules.cpp applies them along a row; the vector kernels are
// tested against it at every level (tests/cpp/test_kernels_rules.cpp).
#pragma once
#include <cstdint>

#include "occseg/params.hpp"

namespace occseg::rules {

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);

// The final state of a voxel whose refined state is s and own state `own`; `region`: it lies in an
// unknown region; `touches`: one of its six neighbours' own state is occupied.
//   rule 1: a clear own value (free or occupied) is the voxel's state;
//   rule 2: at 0.5 inside an unknown region: unknown;
//   rule 3: at 0.5 in a gap: the refined state, but a free gap voxel touching an object is unknown.
inline std::uint8_t voxel_rule(std::uint8_t s, std::uint8_t own, bool region, bool touches) {
  const std::uint8_t gap = ((s == kFree) & touches) ? kUnknown : s;
  return own != kUnknown ? own : (region ? kUnknown : gap);
}

// Rule 3 goes on through the whole gap: a gap voxel that touches an object and came out unknown
// (`result`) seeds the flood of the free gap voxels connected to it.
inline bool gap_seed(std::uint8_t own, bool region, bool touches, std::uint8_t result) {
  return own == kUnknown && !region && touches && result == kUnknown;
}

}  // namespace occseg::rules
