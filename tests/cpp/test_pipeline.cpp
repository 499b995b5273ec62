#include <gtest/gtest.h>

#include <set>

#include "occseg/error.hpp"
#include "occseg/segment.hpp"
#include "synthetic.hpp"

using namespace occseg;
using namespace occseg::test;

namespace {

// Per-voxel state of a noise-free piecewise-constant map: what default must reproduce exactly.
std::vector<std::uint8_t> truth(const Grid& g) {
  std::vector<std::uint8_t> t(g.p.size());
  const Params p;
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = static_cast<std::uint8_t>(p.state_of(g.p[i]));
  return t;
}

std::size_t count_state(const Result& r, State s) {
  std::size_t n = 0;
  for (const Segment& seg : r.segments) n += seg.state == s;
  return n;
}

}  // namespace

TEST(Pipeline, TwoBoxesApartAreTwoOccupiedSegments) {
  for (Preset preset : {Preset::paper, Preset::default_preset}) {
    Grid g(Dims{96, 80, 72}, kFreeP);
    box(g, 10, 10, 10, 30, 30, 30, kOccP);
    box(g, 50, 40, 20, 80, 70, 50, kOccP);
    Params p = preset == Preset::paper ? Params::paper() : Params::defaults();
    const Result r = segment(g, p);
    ASSERT_EQ(count_state(r, State::occupied), 2u) << preset_name(preset);
    const std::uint32_t a = r.labels[g.index(20, 20, 20)], b = r.labels[g.index(60, 50, 30)];
    EXPECT_NE(a, b);
    EXPECT_EQ(r.segments[a].state, State::occupied);
    EXPECT_EQ(r.segments[b].state, State::occupied);
    if (preset == Preset::default_preset) {
      EXPECT_EQ(r.segments[a].voxels, 20u * 20 * 20);
      EXPECT_EQ(r.segments[a].bbox_min, (std::array<std::uint32_t, 3>{10, 10, 10}));
      EXPECT_EQ(r.segments[a].bbox_max, (std::array<std::uint32_t, 3>{29, 29, 29}));
      EXPECT_NEAR(r.segments[a].centroid[0], 19.5, 1e-9);
      EXPECT_NEAR(r.segments[a].mop, kOccP, 1e-6);
    }
  }
}

TEST(Pipeline, UnknownCubeInsideFreeSpaceIsExactlyThatCube) {
  Grid g(Dims{64, 64, 64}, kFreeP);
  box(g, 21, 19, 27, 37, 33, 41, kHalf);  // not aligned to the 8-voxel grid
  const Result r = segment(g, Params::defaults());
  ASSERT_EQ(r.segments.size(), 2u);
  const Segment& u = r.segments[r.labels[g.index(25, 25, 30)]];
  EXPECT_EQ(u.state, State::unknown);
  EXPECT_EQ(u.voxels, 16u * 14 * 14);
  EXPECT_EQ(u.bbox_min, (std::array<std::uint32_t, 3>{21, 19, 27}));
  EXPECT_EQ(u.bbox_max, (std::array<std::uint32_t, 3>{36, 32, 40}));
}

TEST(Pipeline, PaperPresetFindsAlignedUnknownCube) {
  Grid g(Dims{64, 64, 64}, kFreeP);
  box(g, 16, 16, 16, 32, 32, 32, kHalf);
  const Result r = segment(g, Params::paper());
  ASSERT_EQ(r.segments.size(), 2u);
  EXPECT_EQ(r.segments[r.labels[g.index(20, 20, 20)]].voxels, 16u * 16 * 16);
}

TEST(Pipeline, HalfSpacesAtEveryOffsetAreVoxelExactInDefault) {
  const float values[3] = {kFreeP, kHalf, kOccP};
  for (int axis = 0; axis < 3; ++axis)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        if (a == b) continue;
        for (int off = 0; off < 8; ++off) {
          Grid g(Dims{40, 36, 44}, values[a]);
          const int cut = 16 + off;
          for (std::size_t z = 0; z < g.dims.nz; ++z)
            for (std::size_t y = 0; y < g.dims.ny; ++y)
              for (std::size_t x = 0; x < g.dims.nx; ++x) {
                const std::size_t c[3] = {x, y, z};
                if (static_cast<int>(c[axis]) >= cut) g.at(x, y, z) = values[b];
              }
          const Result r = segment(g, Params::defaults());
          EXPECT_EQ(voxel_states(r), truth(g)) << "axis " << axis << " " << a << "->" << b << " offset " << off;
          EXPECT_EQ(r.segments.size(), 2u);
        }
      }
}

TEST(Pipeline, OccupiedVoxelIsNeverFreeInDefault) {
  Grid g(Dims{64, 64, 16}, kFreeP);
  for (int i = 0; i < 40; ++i) g.at((i * 37) % 62 + 1, (i * 11) % 62 + 1, (i * 5) % 14 + 1) = 0.6f;
  const Result r = segment(g, Params::defaults());
  const auto st = voxel_states(r);
  for (std::size_t i = 0; i < st.size(); ++i)
    if (g.p[i] > 0.502f) {
      EXPECT_EQ(st[i], 2) << i;
    }
}

TEST(Pipeline, ThreadCountDoesNotChangeTheResult) {
  Grid g(Dims{100, 90, 70}, kFreeP);
  box(g, 5, 5, 5, 40, 40, 40, kHalf);
  box(g, 50, 20, 10, 70, 60, 60, kOccP);
  for (std::size_t i = 0; i < g.p.size(); i += 13) g.p[i] = 0.5f;  // ray gaps
  for (Params p : {Params::paper(), Params::defaults()}) {
    p.threads = 1;
    const Result one = segment(g, p);
    p.threads = 4;
    const Result four = segment(g, p);
    EXPECT_EQ(one.labels, four.labels);
    ASSERT_EQ(one.segments.size(), four.segments.size());
    for (std::size_t i = 0; i < one.segments.size(); ++i) EXPECT_EQ(one.segments[i].mop, four.segments[i].mop);
  }
}

TEST(Pipeline, AnySizeWorks) {
  for (Dims d : {Dims{1, 1, 1}, Dims{2, 1, 1}, Dims{7, 5, 3}, Dims{130, 3, 1}, Dims{9, 70, 65}}) {
    Grid g(d, kFreeP);
    g.p[g.p.size() / 2] = kOccP;
    const Result r = segment(g, Params::defaults());
    EXPECT_EQ(r.labels.size(), d.count());
    std::uint64_t total = 0;
    for (const Segment& s : r.segments) total += s.voxels;
    EXPECT_EQ(total, d.count());
    EXPECT_EQ(r.segments[r.labels[g.p.size() / 2]].state, State::occupied);
  }
}

TEST(Pipeline, BadInputIsAnErrorNamingTheVoxel) {
  Grid g(Dims{4, 4, 4}, 0.2f);
  g.at(1, 2, 3) = std::numeric_limits<float>::quiet_NaN();
  try {
    segment(g);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::bad_value);
    EXPECT_NE(std::string(e.what()).find("(1, 2, 3)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos);
  }
  g.at(1, 2, 3) = 1.5f;
  EXPECT_THROW(segment(g), Error);
  Dims zero{0, 4, 4};
  EXPECT_THROW(Grid(zero, 0.5f), Error);
}

TEST(Pipeline, ProgressCanCancel) {
  Grid g(Dims{16, 16, 16}, kFreeP);
  Params p;
  std::vector<std::string> seen;
  p.progress = [&](const char* stage, double) {
    seen.push_back(stage);
    return std::string(stage) != "refinement";
  };
  try {
    segment(g, p);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::cancelled);
  }
  EXPECT_EQ(seen.front(), "texture");
  EXPECT_EQ(seen.back(), "refinement");
}
