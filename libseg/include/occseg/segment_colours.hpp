// The colours of segments, shared by every output that shows them (segmentation.png and the 3D
// picture in tools/occseg, segments.ot in liboccseg_octomap, segments.ply in liboccseg_pcl), so
// that a segment has one colour in all of them. Header-only and dependency-free: the adapters
// and the tool include it; it is installed with the C++ headers.
#pragma once
#include <cstdint>

namespace occseg {

struct SegmentColour {
  std::uint8_t r = 0, g = 0, b = 0;
};

// Colour of a state (0 free, 1 unknown, 2 occupied), as the pictures' legend shows it.
inline SegmentColour state_colour_of(std::uint8_t state) {
  switch (state) {
    case 0: return {150, 200, 255};  // free: light blue
    case 1: return {245, 245, 245};  // unknown: white, as in the paper's figures
    default: return {235, 120, 40};  // occupied: orange
  }
}

// Colour of occupied segment `label`: one of eight warm or saturated hues, picked by a
// multiplicative hash of the id, so that neighbouring ids (often neighbouring objects) differ.
// A pure function of the id: the same segment is the same colour in every output and every run.
inline SegmentColour segment_colour(std::uint32_t label) {
  static constexpr SegmentColour hues[8] = {{235, 120, 40}, {200, 40, 40}, {150, 90, 30}, {220, 60, 160},
                                            {230, 185, 30}, {140, 50, 150}, {90, 150, 50}, {250, 100, 100}};
  return hues[(label * 2654435761u >> 16) % 8];
}

}  // namespace occseg
