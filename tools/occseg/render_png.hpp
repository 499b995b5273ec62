// PNG pictures of occupancy maps and segmentations: slices of one or more volumes side by side,
// with captions and a legend, written with libpng. Used by `occseg figures` (Figures 5-7 of the
// paper) and reusable by any command that wants a picture.
//
// Conventions: an xy slice (axis 2) is drawn with y up, an xz slice (axis 1) and a yz slice
// (axis 0) with z up. Probabilities are grey (white 0 = free, black 1 = occupied, mid grey 0.5).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"

namespace occseg::render {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
};

// Colours of the three states (index = occseg::State value) and of occupied segments when they
// are told apart.
Rgb state_colour(std::uint8_t state);
Rgb occupied_colour(std::uint32_t label);

// One volume of a figure (one row): probabilities (greyscale) or states (colour per state). With
// labels, voxels whose label differs from their right or upper neighbour in the slice are drawn
// darker (segment boundaries); with distinct_occupied, each occupied segment gets its own hue.
// The arrays are x fastest, `dims` voxels, and must outlive the call.
struct Volume {
  std::string title;
  Dims dims;
  const float* probability = nullptr;
  const std::uint8_t* states = nullptr;
  const std::uint32_t* labels = nullptr;
  bool distinct_occupied = false;
  // Instead of `states`: the state of each label (indexed by labels[i]), so a segmentation is
  // drawn without a state array as large as the map; only the voxels drawn are looked up.
  const std::uint8_t* label_states = nullptr;
};

// A slice: the axis normal to it (0 x, 1 y, 2 z) and the voxel index along that axis.
struct Slice {
  int axis = 2;
  std::size_t index = 0;
};

struct FigureOptions {
  std::string title;   // drawn above everything ("" for none)
  int scale = 1;       // pixels per voxel
  int shrink = 1;      // voxels per pixel along each axis (every shrink-th voxel is drawn), for large maps
  bool legend = true;  // state colours, boundary, probability ramp
};

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes per pixel, row 0 at the top
  Image() = default;
  Image(int w, int h, Rgb fill);
  void set(int x, int y, Rgb c);
  Rgb get(int x, int y) const;
  void fill_rect(int x, int y, int w, int h, Rgb c);
};

// Draws `text` with the built-in 5 x 7 font (letters are shown in capitals), top-left at (x, y),
// each font pixel `scale` pixels wide. Returns the x after the text.
int draw_text(Image& img, int x, int y, const std::string& text, Rgb colour, int scale = 1);
int text_width(const std::string& text, int scale = 1);

// A grid of panels: one row per volume, one column per slice, each captioned
// "<volume title>  <slice>", then the legend. Throws Error(invalid_argument) when a volume has
// neither probabilities nor states, a slice index is out of range, or the scale or the shrink
// is not 1..16 / 1..64. A panel is ceil(w / shrink) * scale pixels wide for a slice w voxels wide.
Image render_figure(const std::vector<Volume>& rows, const std::vector<Slice>& slices, const FigureOptions& options);

// Writes an 8-bit PNG (indexed colour when the image has at most 256 colours, else RGB),
// encoded straight into the file (no copy of it in memory), atomically: Error(io) naming the path on failure, and no partial file. `into`: as
// write_file_atomically.
void write_png(const std::string& path, const Image& img, StagedFiles* into = nullptr);

}  // namespace occseg::render
