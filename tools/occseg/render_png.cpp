#include "render_png.hpp"

#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <map>

#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/parallel.hpp"

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
  if (s.axis == 2 || s.axis == kTopView) { w = d.nx; h = d.ny; }
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
  if (s.axis == kTopView) return "top view";
  const char* names = "xyz";
  return std::string(1, names[s.axis]) + " = " + std::to_string(s.index);
}

constexpr int kLine = 10;          // a line of text: 7 pixel glyphs and 3 pixels below
constexpr int kLegendLine = 14;    // a line of the legend: 10 pixel swatches and 4 below
constexpr int kMinWidth = 160;
constexpr int kShadeLevels = 6;    // heights of the top view
constexpr Rgb kEmptyColumn{225, 225, 225};
constexpr Rgb kLabelBack{255, 255, 255};
constexpr std::uint64_t kNoKey = ~std::uint64_t(0);
constexpr std::uint32_t kNoSegment = ~std::uint32_t(0);

// Greedy word wrap to lines of at most `max_width` pixels; a word longer than a line is cut.
std::vector<std::string> wrap_words(const std::string& text, int max_width) {
  const std::size_t chars = static_cast<std::size_t>(std::max(1, max_width / 6));
  std::vector<std::string> lines;
  std::string line;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find(' ', pos);
    if (end == std::string::npos) end = text.size();
    std::string word = text.substr(pos, end - pos);
    pos = end + 1;
    if (word.empty()) continue;
    while (word.size() > chars) {  // an overlong word: its own lines
      if (!line.empty()) lines.push_back(line), line.clear();
      lines.push_back(word.substr(0, chars));
      word = word.substr(chars);
    }
    if (line.empty()) line = word;
    else if (line.size() + 1 + word.size() <= chars) line += " " + word;
    else lines.push_back(line), line = word;
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

const char* legend_text(LegendKind k) {
  switch (k) {
    case LegendKind::free: return "free";
    case LegendKind::unknown: return "unknown";
    case LegendKind::occupied: return "occupied";
    case LegendKind::segments: return "occupied: one colour per segment";
    case LegendKind::boundary: return "boundary";
    case LegendKind::empty_column: return "top view: no occupied voxel (lower is darker)";
    case LegendKind::probability: return "p 0 to 1";
  }
  return "";
}

int legend_swatch_width(LegendKind k) {
  if (k == LegendKind::segments) return int(kSegmentPaletteSize) * 3;
  if (k == LegendKind::probability) return 102;
  return 10;
}

// Height level 0..kShadeLevels-1 of voxel row z in a map nz high, and its shading factor.
double height_shade(std::size_t z, std::size_t nz) {
  const std::size_t level = std::min<std::size_t>(kShadeLevels - 1, z * kShadeLevels / std::max<std::size_t>(nz, 1));
  return 0.5 + 0.5 * double(level) / double(kShadeLevels - 1);
}

// One panel before scaling: a colour per pixel, the key telling segments apart for boundaries
// (kNoKey: none) and the occupied segment whose id may be written there (kNoSegment: none).
struct PanelPixels {
  std::size_t w = 0, h = 0;
  std::vector<Rgb> colour;
  std::vector<std::uint64_t> key;
  std::vector<std::uint32_t> segment;
};

// Whether a volume has states (its own or through its labels), and voxel i's.
bool has_states(const Volume& v) { return v.states || (v.labels && v.label_states); }
std::uint8_t state_at(const Volume& v, std::size_t i) {
  if (v.states) return v.states[i];
  const std::uint32_t l = v.labels[i];
  return l < v.label_count ? v.label_states[l] : 1;
}

PanelPixels panel_pixels(const Volume& v, const Slice& s, std::size_t k) {
  std::size_t w, h;
  slice_size(v.dims, s, w, h);
  PanelPixels p;
  p.w = (w + k - 1) / k;
  p.h = (h + k - 1) / k;
  const std::size_t n = p.w * p.h;
  p.colour.assign(n, kBackground);
  p.key.assign(n, kNoKey);
  p.segment.assign(n, kNoSegment);
  const bool distinct = has_states(v) && v.labels && v.distinct_occupied;
  const Dims& d = v.dims;
  if (s.axis == kTopView) {
    // Pixel (u, q) is the column x = u k, y = h - 1 - q k. Layers from the top down, each read
    // row by row (contiguous when k = 1), until every column has found its topmost occupied voxel.
    auto source_row = [&](std::size_t z, std::size_t q) { return d.nx * (h - 1 - q * k) + d.nx * d.ny * z; };
    if (!has_states(v)) {
      std::vector<float> top(n, 0.0f);
      for (std::size_t z = 0; z < d.nz; ++z)
        for (std::size_t q = 0; q < p.h; ++q) {
          const float* src = v.probability + source_row(z, q);
          float* dst = top.data() + q * p.w;
          for (std::size_t u = 0; u < p.w; ++u) dst[u] = dst[u] < src[u * k] ? src[u * k] : dst[u];
        }
      for (std::size_t j = 0; j < n; ++j) p.colour[j] = grey_of(top[j]);
      return p;
    }
    std::vector<std::uint8_t> found(n, 0);
    std::size_t open = n;
    for (std::size_t z = d.nz; z-- > 0 && open > 0;) {
      const double f = height_shade(z, d.nz);
      for (std::size_t q = 0; q < p.h; ++q) {
        const std::size_t base = source_row(z, q);
        const std::uint32_t* lrow = v.labels ? v.labels + base : nullptr;
        const std::uint8_t* srow = v.states ? v.states + base : nullptr;
        const std::uint8_t* table = v.label_states;
        const std::size_t count = v.label_count;
        const std::uint8_t* seen = found.data() + q * p.w;
        for (std::size_t u = 0; u < p.w; ++u) {
          // (Through the labels: the state table, with the labels' row read in place.)
          if (srow) {
            if (srow[u * k] != 2) continue;
          } else {
            const std::uint32_t l = lrow[u * k];
            if (l >= count || table[l] != 2) continue;
          }
          if (seen[u]) continue;
          const std::size_t j = q * p.w + u;
          const std::size_t i = base + u * k;
          found[j] = 1;
          --open;
          p.colour[j] = shade(distinct ? segment_colour(v.labels[i]) : state_colour(2), f);
          p.key[j] = v.labels ? v.labels[i] : 2;
          if (distinct) p.segment[j] = v.labels[i];
        }
      }
    }
    for (std::size_t j = 0; j < n; ++j)
      if (!found[j]) p.colour[j] = kEmptyColumn;
  } else {
    for (std::size_t q = 0; q < p.h; ++q)
      for (std::size_t u = 0; u < p.w; ++u) {
        const std::size_t i = voxel_at(d, s, u * k, q * k, h), j = q * p.w + u;
        if (!has_states(v)) {
          p.colour[j] = grey_of(v.probability[i]);
          continue;
        }
        const std::uint8_t st = state_at(v, i);
        p.colour[j] = state_colour(st);
        if (distinct && st == 2) {
          p.colour[j] = segment_colour(v.labels[i]);
          p.segment[j] = v.labels[i];
        }
        p.key[j] = v.labels ? v.labels[i] : st;
      }
  }
  if (has_states(v)) {  // boundaries: a pixel whose key differs from its right or upper neighbour's
    std::vector<Rgb> edged = p.colour;
    for (std::size_t q = 0; q < p.h; ++q)
      for (std::size_t u = 0; u < p.w; ++u) {
        const std::size_t j = q * p.w + u;
        const bool edge = (u + 1 < p.w && p.key[j + 1] != p.key[j]) || (q > 0 && p.key[j - p.w] != p.key[j]);
        if (edge) edged[j] = darker(p.colour[j]);
      }
    p.colour.swap(edged);
  }
  return p;
}

bool overlaps(const Box& a, const Box& b) {
  return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

// Writes the ids of the larger occupied segments of a panel drawn at `at` (scale pixels per panel
// pixel): at the segment's pixel nearest its centroid in the panel, on a white box, when the
// segment covers at least three times the box and the box overlaps no other id's.
void draw_segment_ids(Image& img, const PanelPixels& p, const Box& at, int scale) {
  struct Stat {
    std::uint64_t count = 0;
    double su = 0, sv = 0;
  };
  // By segment id (a table as long as the largest id drawn; the panel holds them all).
  std::uint32_t top = 0;
  bool any = false;
  for (const std::uint32_t s : p.segment)
    if (s != kNoSegment) top = std::max(top, s), any = true;
  std::vector<Stat> stats(any ? std::size_t(top) + 1 : 0);
  for (std::size_t q = 0; q < p.h; ++q)
    for (std::size_t u = 0; u < p.w; ++u) {
      const std::uint32_t s = p.segment[q * p.w + u];
      if (s == kNoSegment) continue;
      Stat& st = stats[s];
      ++st.count;
      st.su += double(u);
      st.sv += double(q);
    }
  std::vector<std::pair<std::uint32_t, Stat>> order;
  for (std::size_t s = 0; s < stats.size(); ++s)
    if (stats[s].count > 0) order.push_back({std::uint32_t(s), stats[s]});
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
    return a.second.count != b.second.count ? a.second.count > b.second.count : a.first < b.first;
  });
  std::vector<Box> placed;
  constexpr std::size_t kMaxIds = 12;
  for (const auto& [id, st] : order) {
    if (placed.size() == kMaxIds) break;
    const std::string text = std::to_string(id);
    const int bw = text_width(text) + 1, bh = kTextHeight + 2;
    if (double(st.count) * scale * scale < 3.0 * bw * bh) break;  // the rest are smaller still
    const double cu = st.su / double(st.count), cv = st.sv / double(st.count);
    std::size_t best = 0;
    double best_d = -1;
    const std::size_t cj = std::size_t(std::lround(cv)) * p.w + std::size_t(std::lround(cu));
    if (cj < p.segment.size() && p.segment[cj] == id) {
      best = cj;
    } else {
      for (std::size_t j = 0; j < p.segment.size(); ++j) {
        if (p.segment[j] != id) continue;
        const double du = double(j % p.w) - cu, dv = double(j / p.w) - cv, dd = du * du + dv * dv;
        if (best_d < 0 || dd < best_d) best = j, best_d = dd;
      }
    }
    const int px = at.x + int(best % p.w) * scale + scale / 2, py = at.y + int(best / p.w) * scale + scale / 2;
    Box b{px - bw / 2, py - bh / 2, bw, bh};
    b.x = std::clamp(b.x, at.x, std::max(at.x, at.x + at.w - bw));
    b.y = std::clamp(b.y, at.y, std::max(at.y, at.y + at.h - bh));
    if (b.w > at.w || b.h > at.h) continue;
    if (std::any_of(placed.begin(), placed.end(), [&](const Box& o) { return overlaps(o, b); })) continue;
    placed.push_back(b);
    img.fill_rect(b.x, b.y, b.w, b.h, kLabelBack);
    draw_text(img, b.x + 1, b.y + 1, text, kInk);
  }
}

}  // namespace

Rgb state_colour(std::uint8_t state) {
  switch (state) {
    case 0: return {150, 200, 255};  // free: light blue
    case 1: return {245, 245, 245};  // unknown: white, as in the paper's figures
    default: return {235, 120, 40};  // occupied: orange
  }
}

Rgb shade(Rgb c, double f) {
  f = std::clamp(f, 0.0, 1.0);
  return {std::uint8_t(c.r * f), std::uint8_t(c.g * f), std::uint8_t(c.b * f)};
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
  const int x0 = std::max(x, 0), x1 = std::min(x + w, width), y0 = std::max(y, 0), y1 = std::min(y + h, height);
  for (int j = y0; j < y1; ++j)
    for (int i = x0; i < x1; ++i) {
      std::uint8_t* p = &rgb[(std::size_t(j) * width + i) * 3];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
    }
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

FigureLayout layout_figure(const std::vector<Volume>& rows, const std::vector<Slice>& slices, const FigureOptions& o) {
  if (o.scale < 1 || o.scale > 16) throw Error(Status::invalid_argument, "figure scale must be 1..16");
  if (o.shrink < 1 || o.shrink > 64) throw Error(Status::invalid_argument, "figure shrink must be 1..64");
  const std::size_t k = static_cast<std::size_t>(o.shrink);
  auto pixels = [k](std::size_t voxels) { return (voxels + k - 1) / k; };
  if (rows.empty() || slices.empty()) throw Error(Status::invalid_argument, "a figure needs a volume and a slice");
  std::vector<int> panel_w(slices.size(), 0), col_w(slices.size(), 0), row_h(rows.size(), 0);
  bool any_probability = false, any_states = false, any_segments = false, any_plain_occupied = false, any_top = false;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Volume& v = rows[r];
    if (!v.probability && !has_states(v))
      throw Error(Status::invalid_argument, "volume '" + v.title + "' has neither probabilities nor states");
    any_probability |= v.probability != nullptr && !has_states(v);
    any_states |= has_states(v);
    any_segments |= has_states(v) && v.labels && v.distinct_occupied;
    any_plain_occupied |= has_states(v) && !(v.labels && v.distinct_occupied);
    for (std::size_t c = 0; c < slices.size(); ++c) {
      const Slice& s = slices[c];
      const std::size_t n[4] = {v.dims.nx, v.dims.ny, v.dims.nz, 1};
      if (s.axis < 0 || s.axis > kTopView || s.index >= n[s.axis])
        throw Error(Status::invalid_argument, "slice " + (s.axis >= 0 && s.axis <= kTopView ? slice_caption(s) : std::string("axis ") + std::to_string(s.axis)) +
                                                  " is outside volume '" + v.title + "'");
      any_top |= s.axis == kTopView;
      std::size_t w, h;
      slice_size(v.dims, s, w, h);
      panel_w[c] = std::max(panel_w[c], static_cast<int>(pixels(w)) * o.scale);
      row_h[r] = std::max(row_h[r], static_cast<int>(pixels(h)) * o.scale);
    }
  }
  FigureLayout L;
  std::vector<std::string> captions;
  int content = kPad;
  for (std::size_t c = 0; c < slices.size(); ++c) {
    captions.push_back(slice_caption(slices[c]));
    col_w[c] = std::max(panel_w[c], text_width(captions[c]) + kPad);  // captions apart by twice kPad
    content += col_w[c] + kPad;
  }
  std::vector<LegendKind> kinds;
  if (o.legend) {
    if (any_states) kinds.insert(kinds.end(), {LegendKind::free, LegendKind::unknown});
    if (any_plain_occupied) kinds.push_back(LegendKind::occupied);
    if (any_segments) kinds.push_back(LegendKind::segments);
    if (any_states) kinds.push_back(LegendKind::boundary);
    if (any_top && any_states) kinds.push_back(LegendKind::empty_column);
    if (any_probability) kinds.push_back(LegendKind::probability);
  }
  int width = std::max(content, kMinWidth);
  auto item_width = [](LegendKind kind) { return legend_swatch_width(kind) + 4 + text_width(legend_text(kind)); };
  for (LegendKind kind : kinds) width = std::max(width, item_width(kind) + 2 * kPad);
  for (const Volume& v : rows) width = std::max(width, text_width(v.title) + 2 * kPad);
  L.width = width;

  int y = kPad;
  if (!o.title.empty()) {
    for (const std::string& line : wrap_words(o.title, width - 2 * kPad)) {
      L.title.push_back({line, kPad, y});
      y += kLine;
    }
    y += 4;
  }
  int x = kPad;
  for (std::size_t c = 0; c < slices.size(); ++c) {
    L.captions.push_back({captions[c], x, y});
    x += col_w[c] + kPad;
  }
  y += kLine + 4;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    L.row_titles.push_back({rows[r].title, kPad, y});
    y += kLine;
    std::vector<Box> panels;
    x = kPad;
    for (std::size_t c = 0; c < slices.size(); ++c) {
      std::size_t w, h;
      slice_size(rows[r].dims, slices[c], w, h);
      panels.push_back({x, y, static_cast<int>(pixels(w)) * o.scale, static_cast<int>(pixels(h)) * o.scale});
      x += col_w[c] + kPad;
    }
    L.panels.push_back(panels);
    y += row_h[r] + kPad;
  }
  if (!kinds.empty()) {
    x = kPad;
    int ly = y + 2;
    for (LegendKind kind : kinds) {
      const int w = item_width(kind);
      if (x > kPad && x + w > width - kPad) {
        x = kPad;
        ly += kLegendLine;
      }
      const int sw = legend_swatch_width(kind);
      L.legend.push_back({kind, {x, ly, sw, 10}, {legend_text(kind), x + sw + 4, ly + 2}});
      x += w + 10;
    }
    y = ly + kLegendLine;
  }
  L.height = y + kPad;
  return L;
}

Image render_figure(const std::vector<Volume>& rows, const std::vector<Slice>& slices, const FigureOptions& o) {
  const FigureLayout L = layout_figure(rows, slices, o);
  const std::size_t k = static_cast<std::size_t>(o.shrink);
  Image img(L.width, L.height, kBackground);
  for (const TextBox& t : L.title) draw_text(img, t.x, t.y, t.text, kInk);
  for (const TextBox& t : L.captions) draw_text(img, t.x, t.y, t.text, kInk);
  // The panels are independent (a top view reads the whole volume): computed side by side.
  std::vector<PanelPixels> panels(rows.size() * slices.size());
  parallel_for_dynamic(panels.size(), o.threads, [&](std::size_t a, std::size_t b) {
    for (std::size_t i = a; i < b; ++i) panels[i] = panel_pixels(rows[i / slices.size()], slices[i % slices.size()], k);
  });
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Volume& v = rows[r];
    draw_text(img, L.row_titles[r].x, L.row_titles[r].y, L.row_titles[r].text, kInk);
    for (std::size_t c = 0; c < slices.size(); ++c) {
      const Box& at = L.panels[r][c];
      const PanelPixels p = std::move(panels[r * slices.size() + c]);
      if (o.scale == 1) {  // a panel lies inside the image (layout_figure): rows copied straight
        for (std::size_t q = 0; q < p.h; ++q) {
          std::uint8_t* row = &img.rgb[(std::size_t(at.y) + q) * std::size_t(img.width) * 3 + std::size_t(at.x) * 3];
          for (std::size_t u = 0; u < p.w; ++u) {
            const Rgb c = p.colour[q * p.w + u];
            row[3 * u] = c.r, row[3 * u + 1] = c.g, row[3 * u + 2] = c.b;
          }
        }
      } else {
        for (std::size_t q = 0; q < p.h; ++q)
          for (std::size_t u = 0; u < p.w; ++u)
            img.fill_rect(at.x + int(u) * o.scale, at.y + int(q) * o.scale, o.scale, o.scale, p.colour[q * p.w + u]);
      }
      if (has_states(v) && v.labels && v.distinct_occupied) draw_segment_ids(img, p, at, o.scale);
    }
  }
  for (const LegendItem& item : L.legend) {
    const Box& b = item.swatch;
    switch (item.kind) {
      case LegendKind::segments:
        for (std::size_t i = 0; i < kSegmentPaletteSize; ++i) img.fill_rect(b.x + int(i) * 3, b.y, 3, b.h, segment_palette(i));
        break;
      case LegendKind::probability:
        for (int i = 0; i <= 50; ++i) img.fill_rect(b.x + i * 2, b.y, 2, b.h, grey_of(i / 50.0f));
        break;
      case LegendKind::boundary:
        img.fill_rect(b.x, b.y, b.w, b.h, darker(state_colour(0)));
        break;
      case LegendKind::empty_column:
        img.fill_rect(b.x, b.y, b.w, b.h, darker(kEmptyColumn));
        img.fill_rect(b.x + 1, b.y + 1, b.w - 2, b.h - 2, kEmptyColumn);
        break;
      default: {
        const Rgb c = state_colour(item.kind == LegendKind::free ? 0 : item.kind == LegendKind::unknown ? 1 : 2);
        img.fill_rect(b.x, b.y, b.w, b.h, darker(c));
        img.fill_rect(b.x + 1, b.y + 1, b.w - 2, b.h - 2, c);
      }
    }
    draw_text(img, item.text.x, item.text.y, item.text.text, kInk);
  }
  return img;
}

namespace {

struct PngSink {
  std::vector<unsigned char> bytes;
};

void sink_write(png_structp png, png_bytep data, png_size_t n) {
  auto* s = static_cast<PngSink*>(png_get_io_ptr(png));
  s->bytes.insert(s->bytes.end(), data, data + n);
}
void sink_flush(png_structp) {}

// Encodes into memory. Only POD state lives across setjmp; libpng errors longjmp back here.
bool encode(const Image& img, const std::vector<Rgb>& palette, const std::vector<std::uint8_t>& indices,
            PngSink* sink) {
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
  png_set_write_fn(png, sink, sink_write, sink_flush);
  const bool indexed = !palette.empty();
  if (indexed) {
    // Indexed rows are long runs of one index: zlib's run-length strategy (matches at distance 1)
    // and no filter give files about as small as level 6 at a fraction of its time
    // (docs/performance.md, "Reading and writing").
    png_set_compression_level(png, 1);
    png_set_compression_strategy(png, Z_RLE);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
  } else {
    // zlib level 6: within a tenth of level 9 in size, several times faster on large flat areas.
    png_set_compression_level(png, 6);
  }
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
  // Indexed colour when it fits: figures have few colours and compress far better that way.
  std::map<std::uint32_t, std::uint8_t> index;
  std::vector<Rgb> palette;
  std::vector<std::uint8_t> indices(std::size_t(img.width) * img.height);
  std::uint32_t last_key = ~0u;  // not a colour: runs of one colour skip the lookup
  std::vector<std::uint32_t> cache_key(4096, ~0u);
  std::vector<std::uint8_t> cache_index(4096, 0);
  std::uint8_t last_index = 0;
  for (std::size_t i = 0; i < indices.size(); ++i) {
    const std::uint32_t key = (std::uint32_t(img.rgb[3 * i]) << 16) | (img.rgb[3 * i + 1] << 8) | img.rgb[3 * i + 2];
    if (key == last_key) {
      indices[i] = last_index;
      continue;
    }
    // A small cache before the map: boundaries and ids switch among a few colours all the time.
    const std::size_t slot = (key * 2654435761u) >> 20 & 4095u;
    if (cache_key[slot] == key) {
      indices[i] = last_index = cache_index[slot];
      last_key = key;
      continue;
    }
    auto it = index.find(key);
    if (it == index.end()) {
      if (palette.size() == 256) {
        palette.clear();
        break;
      }
      it = index.emplace(key, static_cast<std::uint8_t>(palette.size())).first;
      palette.push_back({img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]});
    }
    indices[i] = last_index = it->second;
    last_key = key;
    cache_key[slot] = key;
    cache_index[slot] = it->second;
  }
  PngSink sink;
  if (!encode(img, palette, indices, &sink)) throw Error(Status::internal, "libpng failed to encode '" + path + "'");
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(sink.bytes.data()), static_cast<std::streamsize>(sink.bytes.size()));
  }, into);
}

}  // namespace occseg::render
