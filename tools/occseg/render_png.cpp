#include "render_png.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>

#include "occseg/error.hpp"
#include "occseg/file_write.hpp"

namespace occseg::render {

namespace {

// 5 x 7 glyphs, one byte per row, bit 4 = leftmost column.
struct Glyph {
  char c;
  std::uint8_t rows[7];
};
const Glyph kFont[] = {
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}}, {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}}, {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}}, {'|', {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}}, {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}}, {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
};

const Glyph* glyph(char c) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  for (const Glyph& g : kFont)
    if (g.c == c) return &g;
  return nullptr;  // space and anything unknown: blank
}

constexpr int kPad = 6;          // pixels around panels
constexpr Rgb kBackground{255, 255, 255};
constexpr Rgb kInk{30, 30, 30};

Rgb darker(Rgb c) { return {std::uint8_t(c.r * 0.55), std::uint8_t(c.g * 0.55), std::uint8_t(c.b * 0.55)}; }

Rgb grey_of(float p) {
  // 51 levels keep the palette small; p = 0.5 is exactly level 25.
  const int level = static_cast<int>(std::lround((1.0 - std::clamp(p, 0.0f, 1.0f)) * 50));
  const std::uint8_t g = static_cast<std::uint8_t>(level * 5);
  return {g, g, g};
}

// Slice geometry: image width/height in voxels, and the voxel index of image pixel (u, v) with
// v = 0 at the top (the largest y or z).
void slice_size(const Dims& d, const Slice& s, std::size_t& w, std::size_t& h) {
  if (s.axis == 2) { w = d.nx; h = d.ny; }
  else if (s.axis == 1) { w = d.nx; h = d.nz; }
  else { w = d.ny; h = d.nz; }
}

std::size_t voxel_at(const Dims& d, const Slice& s, std::size_t u, std::size_t v, std::size_t h) {
  const std::size_t up = h - 1 - v;
  if (s.axis == 2) return u + d.nx * (up + d.ny * s.index);
  if (s.axis == 1) return u + d.nx * (s.index + d.ny * up);
  return s.index + d.nx * (u + d.ny * up);
}

std::string slice_caption(const Slice& s) {
  const char* names = "xyz";
  return std::string(1, names[s.axis]) + " = " + std::to_string(s.index);
}

}  // namespace

Rgb state_colour(std::uint8_t state) {
  switch (state) {
    case 0: return {150, 200, 255};  // free: light blue
    case 1: return {245, 245, 245};  // unknown: white, as in the paper's figures
    default: return {235, 120, 40};  // occupied: orange
  }
}

Rgb occupied_colour(std::uint32_t label) {
  static const Rgb hues[8] = {{235, 120, 40}, {200, 40, 40}, {150, 90, 30}, {220, 60, 160},
                              {230, 185, 30}, {140, 50, 150}, {90, 150, 50}, {250, 100, 100}};
  return hues[(label * 2654435761u >> 16) % 8];
}

Image::Image(int w, int h, Rgb fill) : width(w), height(h), rgb(std::size_t(w) * h * 3) {
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = fill.r;
    rgb[i + 1] = fill.g;
    rgb[i + 2] = fill.b;
  }
}

void Image::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  std::uint8_t* p = &rgb[(std::size_t(y) * width + x) * 3];
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

Rgb Image::get(int x, int y) const {
  const std::uint8_t* p = &rgb[(std::size_t(y) * width + x) * 3];
  return {p[0], p[1], p[2]};
}

void Image::fill_rect(int x, int y, int w, int h, Rgb c) {
  for (int j = y; j < y + h; ++j)
    for (int i = x; i < x + w; ++i) set(i, j, c);
}

int text_width(const std::string& text, int scale) { return static_cast<int>(text.size()) * 6 * scale; }

int draw_text(Image& img, int x, int y, const std::string& text, Rgb colour, int scale) {
  for (char c : text) {
    if (const Glyph* g = glyph(c))
      for (int r = 0; r < 7; ++r)
        for (int k = 0; k < 5; ++k)
          if (g->rows[r] & (0x10 >> k)) img.fill_rect(x + k * scale, y + r * scale, scale, scale, colour);
    x += 6 * scale;
  }
  return x;
}

Image render_figure(const std::vector<Volume>& rows, const std::vector<Slice>& slices, const FigureOptions& o) {
  if (o.scale < 1 || o.scale > 16) throw Error(Status::invalid_argument, "figure scale must be 1..16");
  if (o.shrink < 1 || o.shrink > 64) throw Error(Status::invalid_argument, "figure shrink must be 1..64");
  const std::size_t k = static_cast<std::size_t>(o.shrink);
  auto pixels = [k](std::size_t voxels) { return (voxels + k - 1) / k; };
  if (rows.empty() || slices.empty()) throw Error(Status::invalid_argument, "a figure needs a volume and a slice");
  std::vector<std::size_t> col_w(slices.size(), 0), row_h(rows.size(), 0);
  bool any_probability = false;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Volume& v = rows[r];
    if (!v.probability && !v.states && !(v.label_states && v.labels))
      throw Error(Status::invalid_argument, "volume '" + v.title + "' has neither probabilities nor states");
    any_probability |= v.probability != nullptr;
    for (std::size_t c = 0; c < slices.size(); ++c) {
      const Slice& s = slices[c];
      const std::size_t n[3] = {v.dims.nx, v.dims.ny, v.dims.nz};
      if (s.axis < 0 || s.axis > 2 || s.index >= n[s.axis])
        throw Error(Status::invalid_argument, "slice " + slice_caption(s) + " is outside volume '" + v.title + "'");
      std::size_t w, h;
      slice_size(v.dims, s, w, h);
      col_w[c] = std::max(col_w[c], pixels(w) * o.scale);
      row_h[r] = std::max(row_h[r], pixels(h) * o.scale);
    }
  }
  const int caption = 10, title = o.title.empty() ? 0 : 14, legend = o.legend ? 22 : 0;
  int width = kPad, height = kPad + title;
  for (std::size_t w : col_w) width += static_cast<int>(w) + kPad;
  for (std::size_t h : row_h) height += caption + static_cast<int>(h) + kPad;
  height += legend;
  width = std::max(width, o.legend ? 470 : 0);
  Image img(width, height, kBackground);
  if (!o.title.empty()) draw_text(img, kPad, kPad, o.title, kInk);

  int y0 = kPad + title;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Volume& v = rows[r];
    int x0 = kPad;
    for (std::size_t c = 0; c < slices.size(); ++c) {
      const Slice& s = slices[c];
      draw_text(img, x0, y0, v.title + "  " + slice_caption(s), kInk);
      std::size_t w, h;
      slice_size(v.dims, s, w, h);
      // (u, q): pixel column and row (from the top) of the panel, before scaling; each shows the
      // voxel (u * k, q * k rows below the top) of the slice.
      const std::size_t pw = pixels(w), ph = pixels(h);
      const bool has_states = v.states || (v.label_states && v.labels);
      auto state_at = [&](std::size_t i) -> std::uint8_t { return v.states ? v.states[i] : v.label_states[v.labels[i]]; };
      auto label_at = [&](std::size_t u, std::size_t q) -> std::uint64_t {
        const std::size_t i = voxel_at(v.dims, s, u * k, q * k, h);
        return v.labels ? v.labels[i] : (v.states ? v.states[i] : 0);
      };
      for (std::size_t q = 0; q < ph; ++q)
        for (std::size_t u = 0; u < pw; ++u) {
          const std::size_t i = voxel_at(v.dims, s, u * k, q * k, h);
          Rgb colour;
          if (has_states) {
            const std::uint8_t state = state_at(i);
            colour = state_colour(state);
            if (v.distinct_occupied && v.labels && state == 2) colour = occupied_colour(v.labels[i]);
            const std::uint64_t l = label_at(u, q);
            const bool edge = (u + 1 < pw && label_at(u + 1, q) != l) || (q > 0 && label_at(u, q - 1) != l);
            if (edge) colour = darker(colour);
          } else {
            colour = grey_of(v.probability[i]);
          }
          img.fill_rect(x0 + int(u) * o.scale, y0 + caption + int(q) * o.scale, o.scale, o.scale, colour);
        }
      x0 += static_cast<int>(col_w[c]) + kPad;
    }
    y0 += caption + static_cast<int>(row_h[r]) + kPad;
  }

  if (o.legend) {
    int x = kPad;
    const int y = y0 + 4;
    const char* names[3] = {"free", "unknown", "occupied"};
    for (std::uint8_t s = 0; s < 3; ++s) {
      img.fill_rect(x, y, 10, 10, darker(state_colour(s)));
      img.fill_rect(x + 1, y + 1, 8, 8, state_colour(s));
      x = draw_text(img, x + 14, y + 2, names[s], kInk) + 10;
    }
    img.fill_rect(x, y, 10, 10, darker(state_colour(0)));
    x = draw_text(img, x + 14, y + 2, "boundary", kInk) + 10;
    if (any_probability) {
      x = draw_text(img, x, y + 2, "p 0", kInk) + 3;
      for (int k = 0; k <= 50; ++k) img.fill_rect(x + k * 2, y, 2, 10, grey_of(k / 50.0f));
      draw_text(img, x + 106, y + 2, "1", kInk);
    }
  }
  return img;
}

namespace {

void sink_write(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::ostream*>(png_get_io_ptr(png));
  out->write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(n));
}
void sink_flush(png_structp) {}

// Encodes into `out` (the staged file's stream, whose errors the staging reports). Only POD
// state lives across setjmp; libpng errors longjmp back here. Indexed images get no row filter
// (the usual choice for palettes: their runs compress without one) and zlib level 6, which on
// these pictures is within a few per cent of level 9 at a fraction of its time.
bool encode(const Image& img, const std::vector<Rgb>& palette, const std::vector<std::uint8_t>& indices,
            std::ostream* out) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, out, sink_write, sink_flush);
  png_set_compression_level(png, 6);
  const bool indexed = !palette.empty();
  if (indexed) png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
  png_set_IHDR(png, info, img.width, img.height, 8, indexed ? PNG_COLOR_TYPE_PALETTE : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_color pal[256];
  if (indexed) {
    for (std::size_t k = 0; k < palette.size(); ++k) pal[k] = {palette[k].r, palette[k].g, palette[k].b};
    png_set_PLTE(png, info, pal, static_cast<int>(palette.size()));
  }
  png_write_info(png, info);
  for (int y = 0; y < img.height; ++y) {
    const std::uint8_t* row = indexed ? &indices[std::size_t(y) * img.width] : &img.rgb[std::size_t(y) * img.width * 3];
    png_write_row(png, const_cast<png_bytep>(row));
  }
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

void write_png(const std::string& path, const Image& img, StagedFiles* into) {
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != std::size_t(img.width) * img.height * 3)
    throw Error(Status::invalid_argument, "cannot write an empty or inconsistent image to '" + path + "'");
  // Indexed colour when it fits: figures have few colours and compress far better that way. The
  // palette is found with a small open-addressing table (neighbouring pixels mostly repeat the
  // colour before them, which is checked first).
  std::vector<Rgb> palette;
  std::vector<std::uint8_t> indices(std::size_t(img.width) * img.height);
  constexpr std::size_t kSlots = 1024;  // > 4 x 256: short probes
  std::vector<std::uint32_t> slot_key(kSlots, 0xffffffffu);
  std::vector<std::uint8_t> slot_index(kSlots, 0);
  std::uint32_t last_key = 0xffffffffu;
  std::uint8_t last_index = 0;
  for (std::size_t i = 0; i < indices.size(); ++i) {
    const std::uint32_t key = (std::uint32_t(img.rgb[3 * i]) << 16) | (img.rgb[3 * i + 1] << 8) | img.rgb[3 * i + 2];
    if (key != last_key) {
      std::size_t h = (key * 2654435761u) >> 22;  // 10 bits
      while (slot_key[h] != key && slot_key[h] != 0xffffffffu) h = (h + 1) % kSlots;
      if (slot_key[h] != key) {
        if (palette.size() == 256) {
          palette.clear();
          break;
        }
        slot_key[h] = key;
        slot_index[h] = static_cast<std::uint8_t>(palette.size());
        palette.push_back({img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]});
      }
      last_key = key;
      last_index = slot_index[h];
    }
    indices[i] = last_index;
  }
  write_file_atomically(path, [&](std::ostream& out) {
    // Thrown inside the staging, so the half-written temporary is removed.
    if (!encode(img, palette, indices, &out)) throw Error(Status::internal, "libpng failed to encode '" + path + "'");
  }, into);
}

}  // namespace occseg::render
