// The voxel states as bit rows, with which states each row of voxels holds: what the default
// rules (rules/departures.hpp) leave for the surface band (rules/surface_band.hpp), so that the
// band reads no state byte but those it changes.
#pragma once
#include <cstddef>
#include <cstdint>

#include "util/bit_rows.hpp"

namespace occseg::detail {

// util/bit_rows.hpp's layout (`words` per row of voxels, bits past nx 0), one mask per state; row
// r of the map holds a voxel of a state only if bit kFree, kUnknown or kOccupied of rows[r] is set
// (a superset will do: the flags only let rows be skipped).
struct StateBits {
  static constexpr std::uint8_t kFree = 1, kUnknown = 2, kOccupied = 4;
  const word_t* free = nullptr;
  const word_t* unknown = nullptr;
  const word_t* occupied = nullptr;
  std::size_t words = 0;
  const std::uint8_t* rows = nullptr;
};

// The row's kinds from its three masks' words.
inline std::uint8_t row_kinds(const word_t* f, const word_t* u, const word_t* o, std::size_t words) {
  std::uint64_t af = 0, au = 0, ao = 0;
  for (std::size_t i = 0; i < words; ++i) af |= f[i], au |= u[i], ao |= o[i];
  return static_cast<std::uint8_t>((af ? StateBits::kFree : 0) | (au ? StateBits::kUnknown : 0) |
                                   (ao ? StateBits::kOccupied : 0));
}

}  // namespace occseg::detail
