// PNG pictures of occupancy maps and segmentations: slices of one or more volumes side by side,
// with captions and a legend, written with libpng. Used by `occseg figures` (Figures 5-7 of the
// paper) and reusable by any command that wants a picture.
//
// Conventions: an xy slice (axis 2) is drawn with y up, an xz slice (axis 1) and a yz slice
// (axis 0) with z up; the top view (axis 3) is seen from above, y up. Probabilities are grey
// (white 0 = free, black 1 = occupied, mid grey 0.5).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"
#include "occseg/segment_colour.hpp"

namespace occseg::render {

using occseg::Rgb;

// Colours of the three states (index = occseg::State value). Occupied segments told apart get
// occseg::segment_colour(id), the palette every output shares.
Rgb state_colour(std::uint8_t state);

// A colour scaled by `f` (0..1), each channel rounded down: the shading of faces and heights.
Rgb shade(Rgb c, double f);

// One volume of a figure (one row): probabilities (greyscale) or states (colour per state). With
// labels, voxels whose label differs from their right or upper neighbour in the slice are drawn
// darker (segment boundaries); with distinct_occupied, each occupied segment gets its own hue
// and, with labels, the larger ones carry their id.
// The arrays are x fastest, `dims` voxels, and must outlive the call.
struct Volume {
  std::string title;
  Dims dims;
  const float* probability = nullptr;
  const std::uint8_t* states = nullptr;
  const std::uint32_t* labels = nullptr;
  bool distinct_occupied = false;
  // Instead of `states`: the state of each label (label_count of them), a voxel's state being
  // that of its label; so a segmentation is drawn from its labels without a volume of states.
  const std::uint8_t* label_states = nullptr;
  std::size_t label_count = 0;
};

// A slice: the axis normal to it (0 x, 1 y, 2 z) and the voxel index along that axis; or axis 3,
// the top view: for each (x, y) column the topmost occupied voxel (its segment's or state's colour,
// darker the lower it lies; a grey where the column holds none), or the largest probability of
// the column in a probability row.
struct Slice {
  int axis = 2;
  std::size_t index = 0;
};
constexpr int kTopView = 3;

struct FigureOptions {
  std::string title;   // drawn above everything ("" for none)
  int scale = 1;       // pixels per voxel
  int shrink = 1;      // voxels per pixel along each axis (every shrink-th voxel is drawn), for large maps
  bool legend = true;  // the colours the rows use (layout_figure: LegendKind), the probability ramp
  int threads = 1;     // panels computed on up to this many threads (0: all cores); the same image
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

// Where everything of a figure goes (pixels, row 0 at the top). Text boxes are text_width wide
// and kTextHeight high; every box lies inside the image and no two overlap (the title is wrapped
// at spaces to the image's width, the legend flows onto as many lines as it needs, a column is as
// wide as its widest caption or panel).
constexpr int kTextHeight = 7;
struct Box {
  int x = 0, y = 0, w = 0, h = 0;
};
struct TextBox {
  std::string text;
  int x = 0, y = 0;
};
enum class LegendKind { free, unknown, occupied, segments, boundary, empty_column, probability };
struct LegendItem {
  LegendKind kind;
  Box swatch;    // the colour sample (the ramp for `probability`)
  TextBox text;
};
struct FigureLayout {
  int width = 0, height = 0;
  std::vector<TextBox> title;                // one per line
  std::vector<TextBox> captions;             // one per column, above the first row
  std::vector<TextBox> row_titles;           // one per row, above its panels
  std::vector<std::vector<Box>> panels;      // [row][column]
  std::vector<LegendItem> legend;
};

// A grid of panels: the title, a caption per column ("z = 16", "top view"), one row per volume
// under its title, then the legend. Throws Error(invalid_argument) when a volume has neither
// probabilities nor states, a slice index is out of range, or the scale or the shrink is not
// 1..16 / 1..64. A panel is ceil(w / shrink) * scale pixels wide for a slice w voxels wide.
FigureLayout layout_figure(const std::vector<Volume>& rows, const std::vector<Slice>& slices,
                           const FigureOptions& options);
Image render_figure(const std::vector<Volume>& rows, const std::vector<Slice>& slices, const FigureOptions& options);

// Writes an 8-bit PNG (indexed colour when the image has at most 256 colours, else RGB)
// atomically: Error(io) naming the path on failure, and no partial file. `into`: as
// write_file_atomically.
void write_png(const std::string& path, const Image& img, StagedFiles* into = nullptr);

}  // namespace occseg::render
