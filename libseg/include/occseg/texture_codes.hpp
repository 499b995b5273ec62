// Texture codes: what a texture operator (built-in or a plugin's) hands to the division.
#pragma once
#include <cstdint>
#include <vector>

namespace occseg {

// Code value marking a voxel on the map's outer faces: it has no texture unit.
constexpr std::uint16_t kNoTexture = 0xFFFF;

struct TextureMap {
  std::vector<std::uint16_t> codes;  // lbp * bins + contrast level, or kNoTexture
  int bins = 0;                      // contrast levels
  int codes_total = 0;               // distinct codes of other operators (registry.hpp); 0: 64 * bins
  int code_count() const { return codes_total ? codes_total : 64 * bins; }
};

}  // namespace occseg
