#include <gtest/gtest.h>

#include <cmath>

#include "occseg/create.hpp"
#include "occseg/refine.hpp"
#include "occseg/texture.hpp"
#include "own_states_internal.hpp"
#include "random_maps.hpp"

using namespace occseg;

TEST(Create, MopAndStateIntervals) {
  Grid g(Dims{4, 2, 1}, 0.0f);
  // Left 2x2 block: mean 0.5 (unknown); right 2x2 block: mean 0.503 (occupied).
  g.at(0, 0, 0) = 0.4f; g.at(1, 0, 0) = 0.6f; g.at(0, 1, 0) = 0.5f; g.at(1, 1, 0) = 0.5f;
  g.at(2, 0, 0) = 0.503f; g.at(3, 0, 0) = 0.503f; g.at(2, 1, 0) = 0.503f; g.at(3, 1, 0) = 0.503f;
  Block l{{0, 0, 0}, {2, 2, 1}}, r{{2, 0, 0}, {4, 2, 1}};
  EXPECT_NEAR(mean_occupancy(g, l), 0.5, 1e-7);
  const auto st = create_segments(g, {l, r}, Params());
  EXPECT_EQ(st[g.index(0, 0, 0)], 1);  // unknown although the voxel itself is 0.4
  EXPECT_EQ(st[g.index(3, 1, 0)], 2);
  Params p;
  EXPECT_EQ(p.state_of(0.4979), State::free);
  EXPECT_EQ(p.state_of(0.498), State::unknown);
  EXPECT_EQ(p.state_of(0.502), State::unknown);
  EXPECT_EQ(p.state_of(0.5021), State::occupied);
}

TEST(Create, OwnStatesFoundDuringCreationMatchTheirDefinition) {
  // Values on the band's edges and one float either side of them, where the float thresholds
  // must agree with the double comparisons of Params::state_of.
  Params base;
  std::vector<float> edges;
  for (double t : {base.free_below, base.occupied_above}) {
    const float f = static_cast<float>(t);
    edges.insert(edges.end(), {std::nextafter(f, 0.0f), f, std::nextafter(f, 1.0f)});
  }
  const Dims dims[] = {{37, 29, 21}, {64, 64, 32}, {8, 1, 19}, {13, 70, 9}};
  for (std::size_t k = 0; k < 4; ++k) {
    Grid g = test::random_map(dims[k], 40 + k, 0.3);
    for (std::size_t i = k; i < g.p.size(); i += 7) g.p[i] = edges[(i / 7) % edges.size()];
    Params p;
    p.threads = 1 + static_cast<int>(k % 3);
    const std::vector<Block> blocks = divide(g, compute_texture(g, p.contrast_bins, p.threads), p);
    std::vector<std::uint8_t> own(g.p.size(), 7);  // 7: never written
    const std::vector<std::uint8_t> st = detail::create_segments_and_own_states(g, blocks, p, own.data());
    EXPECT_EQ(st, create_segments(g, blocks, p)) << "map " << k;
    ASSERT_EQ(own.size(), g.p.size());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < own.size(); ++i) wrong += own[i] != static_cast<std::uint8_t>(p.state_of(g.p[i]));
    EXPECT_EQ(wrong, 0u) << "map " << k;
    EXPECT_EQ(own, own_states(g, p)) << "map " << k;
  }
}
