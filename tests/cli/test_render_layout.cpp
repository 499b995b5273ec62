// The layout of segmentation.png (tools/occseg/render_png.cpp): at any map size every text lies
// inside the picture and nothing overlaps anything else (issue 25: on a narrow map the captions
// printed over each other and the title was cut). And the palette every output shares.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "occseg/segment_colour.hpp"
#include "render_png.hpp"

namespace occseg::render {
namespace {

Box text_box(const TextBox& t) { return {t.x, t.y, text_width(t.text), kTextHeight}; }

bool overlap(const Box& a, const Box& b) {
  return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

// Every box inside the picture, no two overlapping; `what` names each for the failure message.
void expect_fits(const FigureLayout& L, const std::string& name) {
  std::vector<std::pair<std::string, Box>> boxes;
  for (const TextBox& t : L.title) boxes.push_back({"title '" + t.text + "'", text_box(t)});
  for (const TextBox& t : L.captions) boxes.push_back({"caption '" + t.text + "'", text_box(t)});
  for (const TextBox& t : L.row_titles) boxes.push_back({"row title '" + t.text + "'", text_box(t)});
  for (std::size_t r = 0; r < L.panels.size(); ++r)
    for (std::size_t c = 0; c < L.panels[r].size(); ++c)
      boxes.push_back({"panel " + std::to_string(r) + "," + std::to_string(c), L.panels[r][c]});
  for (const LegendItem& item : L.legend) {
    boxes.push_back({"legend swatch of '" + item.text.text + "'", item.swatch});
    boxes.push_back({"legend '" + item.text.text + "'", text_box(item.text)});
  }
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const Box& b = boxes[i].second;
    EXPECT_TRUE(b.x >= 0 && b.y >= 0 && b.x + b.w <= L.width && b.y + b.h <= L.height)
        << name << ": " << boxes[i].first << " at (" << b.x << ", " << b.y << ") size " << b.w << " x " << b.h
        << " is outside the " << L.width << " x " << L.height << " picture";
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      EXPECT_FALSE(overlap(b, boxes[j].second)) << name << ": " << boxes[i].first << " overlaps " << boxes[j].first;
  }
}

// A figure like segmentation.png's for a map of `d`: four z levels (or every one), a y, an x
// slice and the top view for 3D maps; rows map, segments (and the ideal state).
struct Figure {
  std::vector<float> p;
  std::vector<std::uint8_t> states;
  std::vector<std::uint32_t> labels;
  std::vector<Volume> rows;
  std::vector<Slice> slices;
  FigureOptions options;

  Figure(Dims d, const std::string& title, bool ideal) : p(d.count(), 0.2f), states(d.count(), 0), labels(d.count(), 0) {
    for (std::size_t i = 0; i < d.count(); i += 3) states[i] = 2, labels[i] = std::uint32_t(1 + i % 5), p[i] = 0.9f;
    rows.push_back({"map", d, p.data(), nullptr, nullptr, false});
    rows.push_back({"segments", d, nullptr, states.data(), labels.data(), true});
    if (ideal) rows.push_back({"ideal state", d, nullptr, states.data(), nullptr, false});
    if (d.nz >= 4) {
      for (std::size_t k = 0; k < 4; ++k) slices.push_back({2, (2 * k + 1) * d.nz / 8});
    } else {
      for (std::size_t z = 0; z < d.nz; ++z) slices.push_back({2, z});
    }
    if (d.nz > 1) {
      slices.push_back({1, d.ny / 2});
      slices.push_back({0, d.nx / 2});
      slices.push_back({kTopView, 0});
    }
    options.title = title;
    const std::size_t m = std::max({d.nx, d.ny, d.nz});
    options.shrink = static_cast<int>((m + 639) / 640);
    options.scale = static_cast<int>(std::clamp<std::size_t>(256 / m, 1, 8));
  }
};

TEST(FigureLayout, NarrowTableSceneFits) {
  // The table scene at 2 cm: 59 x 35 x 131 voxels, one pixel per voxel; the picture used to be
  // 470 pixels wide with its title cut and its captions over each other.
  Figure f({59, 35, 131}, "occseg segment table_scene_mug_stereo_textured.pcd  (59 x 35 x 131, preset default)", false);
  const FigureLayout L = layout_figure(f.rows, f.slices, f.options);
  expect_fits(L, "table scene");
  EXPECT_GE(L.title.size(), 2u);  // wrapped, not cut
  std::string joined;
  for (const TextBox& t : L.title) joined += (joined.empty() ? "" : " ") + t.text;
  EXPECT_EQ(joined, "occseg segment table_scene_mug_stereo_textured.pcd (59 x 35 x 131, preset default)");  // every word
  ASSERT_EQ(L.captions.size(), 7u);
  EXPECT_EQ(L.captions.back().text, "top view");
  const Image img = render_figure(f.rows, f.slices, f.options);
  EXPECT_EQ(img.width, L.width);
  EXPECT_EQ(img.height, L.height);
}

TEST(FigureLayout, AnyMapSizeFits) {
  const Dims sizes[] = {{1, 1, 1}, {1, 200, 3}, {3, 3, 300}, {640, 2, 2}, {2, 2, 2}, {5, 7, 4}, {2000, 10, 10}, {48, 1, 1}};
  for (const Dims& d : sizes)
    for (const char* title : {"", "t", "a very long title that certainly does not fit on one line of a small picture",
                              "anunbrokenwordlongerthananylineofthepicturecanholdatallxxxxxxxxxxxxxxxxxxxxxxxxxxx"})
      for (bool ideal : {false, true}) {
        Figure f(d, title, ideal);
        const std::string name = std::to_string(d.nx) + " x " + std::to_string(d.ny) + " x " + std::to_string(d.nz) +
                                 (ideal ? ", ideal" : "") + ", title '" + title + "'";
        expect_fits(layout_figure(f.rows, f.slices, f.options), name);
      }
}

TEST(FigureLayout, LegendShowsTheColoursUsed) {
  Figure f({20, 20, 8}, "", false);
  FigureLayout L = layout_figure(f.rows, f.slices, f.options);
  std::vector<LegendKind> kinds;
  for (const LegendItem& i : L.legend) kinds.push_back(i.kind);
  // Segments in their own colours: the palette, no single "occupied" colour.
  EXPECT_EQ(kinds, (std::vector<LegendKind>{LegendKind::free, LegendKind::unknown, LegendKind::segments,
                                            LegendKind::boundary, LegendKind::empty_column, LegendKind::probability}));
  const Image img = render_figure(f.rows, f.slices, f.options);
  for (const LegendItem& i : L.legend) {
    if (i.kind != LegendKind::segments) continue;
    for (std::size_t k = 0; k < kSegmentPaletteSize; ++k)
      EXPECT_EQ(img.get(i.swatch.x + int(k) * 3 + 1, i.swatch.y + 5), segment_palette(k)) << k;
  }
  // With an ideal state (states without segments) the orange of occupied space is listed too.
  Figure g({20, 20, 8}, "", true);
  L = layout_figure(g.rows, g.slices, g.options);
  kinds.clear();
  for (const LegendItem& i : L.legend) kinds.push_back(i.kind);
  EXPECT_EQ(kinds[2], LegendKind::occupied);
  EXPECT_EQ(kinds[3], LegendKind::segments);
}

TEST(SegmentColour, OnePaletteForEveryOutput) {
  // Ids map to the documented palette; consecutive ids differ; no hue is a state colour.
  EXPECT_EQ(segment_colour(0), segment_palette(0));
  for (std::uint32_t id = 0; id < 1000; ++id) {
    EXPECT_EQ(segment_colour(id), segment_palette(((id * 2654435761u) >> 16) % 16));
    EXPECT_NE(segment_colour(id), segment_colour(id + 1)) << id;
    EXPECT_NE(segment_colour(id), state_colour(0));
    EXPECT_NE(segment_colour(id), state_colour(1));
  }
}

}  // namespace
}  // namespace occseg::render
