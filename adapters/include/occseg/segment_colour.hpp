// The one palette of occupied segments, shared by every output that colours them (the slices of
// segmentation.png, the 3D picture scene.png, segments.ot, segments.ply), so a segment has the
// same colour everywhere. Header only, no dependencies: any writer may include it.
//
// A segment's colour depends on its id alone (not on the other segments), so the colour of a
// segment never changes when an output is written on its own. Sixteen hues, none of them the light
// blue of free space, the near white of unknown space or a grey of the probability ramp; ids are
// scattered over them by a multiplicative hash. Consecutive ids never share a hue: one more id
// moves the index by 7 or 8 (mod 16).
#pragma once
#include <cstddef>
#include <cstdint>

namespace occseg {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  constexpr bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  constexpr bool operator!=(const Rgb& o) const { return !(*this == o); }
};

constexpr std::size_t kSegmentPaletteSize = 16;

// The palette in order (index 0..15); docs/cli.md lists it.
constexpr Rgb segment_palette(std::size_t k) {
  constexpr Rgb hues[kSegmentPaletteSize] = {
      {235, 120, 40}, {200, 40, 40},  {150, 90, 30},   {220, 60, 160}, {230, 185, 30}, {140, 50, 150},
      {90, 150, 50},  {250, 100, 100}, {30, 130, 130}, {50, 70, 170},  {170, 170, 40}, {120, 210, 110},
      {110, 70, 220}, {240, 150, 200}, {130, 30, 70},  {160, 220, 60}};
  return hues[k % kSegmentPaletteSize];
}

// Which palette entry segment `id` gets: bits 16.. of id * 2654435761 (mod 2^32), modulo 16.
constexpr std::size_t segment_palette_index(std::uint32_t id) {
  return static_cast<std::size_t>((static_cast<std::uint32_t>(id * 2654435761u) >> 16) % kSegmentPaletteSize);
}

// The colour of occupied segment `id`.
constexpr Rgb segment_colour(std::uint32_t id) { return segment_palette(segment_palette_index(id)); }

}  // namespace occseg
