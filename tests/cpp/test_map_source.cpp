// A map read through a converter (Grid::source, the C ABI's view of a non-float32 or strided
// buffer): segment() and the stages that read the values give what they give for the same floats
// stored as a float array, bit for bit, read no run larger than a plane (no whole copy of the
// map), and fail with the source's own error for a bad value.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/grid.hpp"
#include "occseg/segment.hpp"
#include "random_maps.hpp"
#include "stages/create.hpp"
#include "stages/refine.hpp"
#include "stages/texture.hpp"

namespace occseg {
namespace {

// uint16 values, x fastest, converted as the C ABI converts them (v / 65535, then to float); the
// value 65535 + 1 does not exist, so bad voxels are marked apart (bad_at).
class U16Source final : public MapSource {
 public:
  U16Source(const Grid& floats) : dims_(floats.dims), v_(floats.dims.count()) {
    for (std::size_t i = 0; i < v_.size(); ++i) v_[i] = static_cast<std::uint16_t>(std::lround(floats.p[i] * 65535.0));
  }
  static float convert(std::uint16_t v) { return static_cast<float>(v / 65535.0); }
  bool read(std::size_t i, std::size_t n, float* out) const override {
    std::size_t seen = largest.load();
    while (n > seen && !largest.compare_exchange_weak(seen, n)) {
    }
    for (std::size_t k = 0; k < n; ++k) {
      if (i + k == bad_at) return false;
      out[k] = convert(v_[i + k]);
    }
    return true;
  }
  [[noreturn]] void fail() const override {
    throw Error(Status::bad_value, "test source: voxel " + std::to_string(bad_at) + " is bad");
  }
  // The same values as a float array.
  Grid floats() const {
    Grid g(dims_, 0.0f);
    for (std::size_t i = 0; i < v_.size(); ++i) g.p[i] = convert(v_[i]);
    return g;
  }
  Grid view() const {
    Grid g;
    g.dims = dims_;
    g.source = this;
    return g;
  }
  std::size_t bad_at = ~std::size_t(0);
  mutable std::atomic<std::size_t> largest{0};

 private:
  Dims dims_;
  std::vector<std::uint16_t> v_;
};

void expect_same(const Result& a, const Result& b) {
  ASSERT_EQ(a.labels.size(), b.labels.size());
  EXPECT_TRUE(std::equal(a.labels.begin(), a.labels.end(), b.labels.begin()));
  ASSERT_EQ(a.segments.size(), b.segments.size());
  for (std::size_t i = 0; i < a.segments.size(); ++i) {
    EXPECT_EQ(a.segments[i].voxels, b.segments[i].voxels) << i;
    EXPECT_EQ(a.segments[i].mop, b.segments[i].mop) << i;  // the labelling's sums of the values
    EXPECT_EQ(a.segments[i].kind, b.segments[i].kind) << i;
  }
}

TEST(MapSource, SegmentThroughASourceIsBitIdenticalAndReadsNoMoreThanAPlaneAtATime) {
  // Odd sizes, several of the texture pass's groups of planes, and maps with an axis of size 1
  // (the stencil without that axis).
  for (Dims d : {Dims{37, 29, 41}, Dims{64, 48, 70}, Dims{40, 33, 1}, Dims{25, 1, 30}, Dims{1, 20, 20}}) {
    const U16Source src(test::random_map(d, d.nx * 131 + d.nz, 0.6));
    const Grid floats = src.floats(), view = src.view();
    for (Params p : {Params::paper(), Params::defaults()})
      for (int threads : {1, 2, 3}) {
        p.threads = threads;
        src.largest = 0;
        const Result through = segment(view, p);
        EXPECT_LE(src.largest.load(), d.nx * d.ny) << d.nx << "x" << d.ny << "x" << d.nz;
        expect_same(segment(floats, p), through);
      }
  }
}

TEST(MapSource, ATextureOperatorThatTakesFloatsGetsTheMapConvertedWhole) {
  // lbp8 (the 2D operator) is called through the plugin interface, with a float array.
  const U16Source src(test::random_map(Dims{40, 33, 1}, 5, 0.6));
  Params p = Params::defaults();
  p.texture = "lbp8";
  expect_same(segment(src.floats(), p), segment(src.view(), p));
  EXPECT_GT(src.largest.load(), 40u);  // converted whole, in runs of many rows (with_float_values)
}

TEST(MapSource, TheStagesOnTheirOwnReadTheSameValues) {
  const U16Source src(test::random_map(Dims{30, 26, 22}, 7, 0.5));
  const Grid floats = src.floats(), view = src.view();
  EXPECT_EQ(view.value(5 + 30 * (6 + 26 * 7)), floats.p[5 + 30 * (6 + 26 * 7)]);
  EXPECT_EQ(own_states(view, Params()), own_states(floats, Params()));
  const TextureMap a = compute_texture(floats, 8, 2), b = compute_texture(view, 8, 2);
  EXPECT_EQ(a.codes, b.codes);
  // Blocks off the lattice of the creation's cells: each block's mean is read from the map.
  std::vector<Block> blocks;
  for (std::uint32_t z = 0; z < 22; z += 11)
    for (std::uint32_t y = 0; y < 26; y += 13)
      for (std::uint32_t x = 0; x < 30; x += 5) blocks.push_back(Block{{x, y, z}, {x + 5, y + 13, z + 11}});
  for (const Block& b : blocks) EXPECT_EQ(mean_occupancy(view, b), mean_occupancy(floats, b));
  EXPECT_EQ(create_segments(view, blocks, Params()), create_segments(floats, blocks, Params()));
  const Grid copy = with_float_values(view, 2);
  EXPECT_EQ(copy.source, nullptr);
  EXPECT_EQ(copy.p, floats.p);
}

TEST(MapSource, ABadValueFailsWithTheSourcesError) {
  U16Source src(test::random_map(Dims{33, 21, 40}, 3, 0.3));
  src.bad_at = 33 * 21 * 27 + 33 * 4 + 9;  // deep in the map: after other groups of planes
  for (Params p : {Params::paper(), Params::defaults()})
    for (int threads : {1, 2}) {
      p.threads = threads;
      try {
        segment(src.view(), p);
        FAIL() << "no error";
      } catch (const Error& e) {
        EXPECT_EQ(e.status(), Status::bad_value);
        EXPECT_EQ(std::string(e.what()), "test source: voxel " + std::to_string(src.bad_at) + " is bad");
      }
    }
  EXPECT_THROW(check_probabilities(src.view()), Error);
  EXPECT_THROW(with_float_values(src.view()), Error);
}

}  // namespace
}  // namespace occseg
