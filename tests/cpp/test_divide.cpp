#include <gtest/gtest.h>

#include <algorithm>

#include "isa_levels.hpp"
#include "random_maps.hpp"
#include "stages/codes.hpp"
#include "stages/divide.hpp"
#include "stages/histogram.hpp"

using namespace occseg;

TEST(Divide, ShouldSplitFollowsEquation2) {
  // Three histograms with G(a,b) = G(a,c) = 40 ln 2 and G(b,c) = 0: Gmin = 0 -> split.
  std::vector<std::uint32_t> a{10, 0}, b{0, 10}, c{0, 10};
  EXPECT_TRUE(should_split({a.data(), b.data(), c.data()}, 2, 1.2));
  // Identical histograms: all G = 0 -> uniform, no split.
  EXPECT_FALSE(should_split({b.data(), c.data()}, 2, 1.2));
  // One pair only: Gmax = Gmin -> R = 1, never above X = 1.2.
  EXPECT_FALSE(should_split({a.data(), b.data()}, 2, 1.2));
  // Fewer than two histograms: no evidence.
  EXPECT_FALSE(should_split({a.data()}, 2, 1.2));
  // R just above and below X.
  std::vector<std::uint32_t> d{30, 10}, e{10, 30}, f{25, 15};
  const double gde = g_statistic(d.data(), e.data(), 2), gdf = g_statistic(d.data(), f.data(), 2),
               gef = g_statistic(e.data(), f.data(), 2);
  const double r = std::max({gde, gdf, gef}) / std::min({gde, gdf, gef});
  EXPECT_TRUE(should_split({d.data(), e.data(), f.data()}, 2, r * 0.999));
  EXPECT_FALSE(should_split({d.data(), e.data(), f.data()}, 2, r * 1.001));
}

TEST(Divide, UniformMapStaysInTopBlocks) {
  Grid g(Dims{100, 70, 64}, 0.3f);
  Params p;
  const std::vector<Block> b = divide(g, compute_texture(g, 8, 1), p);
  // 2 x 2 x 1 top blocks, clipped by the far faces, none split.
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[1].lo[0], 64u);
  EXPECT_EQ(b[1].hi[0], 100u);
  EXPECT_EQ(b[2].hi[1], 70u);
  std::uint64_t vol = 0;
  for (const Block& k : b) vol += k.volume();
  EXPECT_EQ(vol, g.dims.count());
}

TEST(Divide, ObjectForcesSplitDownToSmin) {
  Grid g(Dims{64, 64, 64}, 0.2f);
  for (int z = 10; z < 14; ++z)
    for (int y = 10; y < 14; ++y)
      for (int x = 10; x < 14; ++x) g.at(x, y, z) = 0.9f;
  Params p;
  const std::vector<Block> b = divide(g, compute_texture(g, 8, 1), p);
  bool found_small = false;
  std::uint64_t vol = 0;
  for (const Block& k : b) {
    vol += k.volume();
    if (k.lo[0] <= 10 && k.hi[0] > 10 && k.lo[1] <= 10 && k.hi[1] > 10 && k.lo[2] <= 10 && k.hi[2] > 10)
      found_small = (k.hi[0] - k.lo[0]) == 8;
  }
  EXPECT_TRUE(found_small);
  EXPECT_EQ(vol, g.dims.count());
  EXPECT_GT(b.size(), 8u);
}

TEST(Divide, TinyAndFlatMapsAreCovered) {
  for (Dims d : {Dims{1, 1, 1}, Dims{5, 3, 2}, Dims{70, 9, 1}, Dims{1, 1, 130}}) {
    Grid g(d, 0.1f);
    g.p[g.p.size() / 2] = 0.9f;
    const std::vector<Block> b = divide(g, compute_texture(g, 8, 1), Params());
    std::uint64_t vol = 0;
    for (const Block& k : b) vol += k.volume();
    EXPECT_EQ(vol, d.count()) << d.nx << "x" << d.ny << "x" << d.nz;
  }
}

TEST(Divide, SameLeavesForAnyThreadCount) {
  Grid g(Dims{130, 70, 40}, 0.2f);
  for (std::size_t i = 0; i < g.p.size(); i += 7) g.p[i] = 0.5f + 0.4f * ((i / 7) % 3 == 0);
  Params p1, p2;
  p1.threads = 1;
  p2.threads = 3;
  const TextureMap t = compute_texture(g, 8, 1);
  const auto a = divide(g, t, p1), b = divide(g, t, p2);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a[i].lo[k], b[i].lo[k]);
  EXPECT_EQ(compute_texture(g, 8, 4).codes, t.codes);
}

TEST(Divide, CountCodesMatchesOneByOneCounting) {
  // Codes in runs: whole rows of one code (the eight-at-once path), rows with one voxel
  // different at each position, kNoTexture runs and single kNoTexture voxels; blocks at every
  // offset and width, so rows of 8 start anywhere and leave tails of 1..7, and of 1 to 8 rows
  // (blocks 8 wide go four rows at a time where they can, then two, then one). The counting kernel
  // of every level the processor has; the packing ones take the block's first code as the common
  // one, kNoTexture included.
  const Dims d{37, 9, 4};
  TextureMap t;
  t.bins = 8;
  t.codes.resize(d.count());
  std::uint32_t s = 12345;
  auto rnd = [&] { return s = s * 1103515245u + 12345u, (s >> 16) & 0x7FFF; };
  for (std::size_t i = 0; i < t.codes.size();) {
    const std::size_t run = 1 + rnd() % 20;
    const std::uint16_t c = rnd() % 5 == 0 ? kNoTexture : static_cast<std::uint16_t>(rnd() % 512);
    for (std::size_t k = 0; k < run && i < t.codes.size(); ++k, ++i) t.codes[i] = c;
    if (rnd() % 3 == 0 && i < t.codes.size()) t.codes[i++] = static_cast<std::uint16_t>(rnd() % 512);
  }
  for (std::uint32_t x = 0; x < 12; x += 3) t.codes[x + d.nx] = kNoTexture;  // blocks whose first voxel has none
  std::size_t checked = 0, uniform_rows = 0, first_without_texture = 0;
  testing_isa::for_each_isa([&](kernels::Isa) {
    for (std::uint32_t x0 = 0; x0 < 12; ++x0)
      for (std::uint32_t w = 1; x0 + w <= d.nx; w += w < 9 ? 1 : 5)  // 8: the four-row path
        for (std::uint32_t rows = 1; rows <= 8; ++rows) {
          const Block b{{x0, 1, 0}, {x0 + w, 1 + rows, 4}};
          std::vector<std::uint32_t> got(512, 7), want(512, 0);
          count_codes(t, d, b, 512, got.data());
          for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
            for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
              for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) {
                const std::uint16_t c = t.codes[x + d.nx * (y + d.ny * z)];
                if (c != kNoTexture) ++want[c];
              }
          ASSERT_EQ(got, want) << "block x " << x0 << " width " << w << " rows " << rows;
          ++checked;
          first_without_texture += t.codes[x0 + d.nx] == kNoTexture;
        }
  });
  EXPECT_GT(first_without_texture, 10u);
  // The map really has rows of eight equal codes, with and without texture.
  for (std::size_t i = 0; i + 8 <= t.codes.size(); ++i)
    uniform_rows += std::all_of(t.codes.begin() + i, t.codes.begin() + i + 8, [&](auto c) { return c == t.codes[i]; });
  EXPECT_GT(uniform_rows, 50u);
  EXPECT_GT(checked, 1000u);
}

// Eq. (2) stopping at the first pairs that say "split" gives the answer of all 28 pairs: on
// random statistics with ties, zeros and ratios at X, in every position of the pair order.
TEST(Divide, SplitRuleStopsEarlyWithTheAnswerOfEveryPair) {
  test::Rng r(9);
  std::size_t early = 0, splits = 0, trials = 0;
  for (std::size_t n = 0; n <= 8; ++n)
    for (int trial = 0; trial < 400; ++trial) {
      double g[8][8];
      for (auto& row : g)
        for (double& v : row) {
          const int kind = r.below(8);
          v = kind == 0 ? 0.0 : kind == 1 ? 1.0 : kind == 2 ? 1.2 : 1.0 + r.uniform();
        }
      std::size_t asked = 0, asked_all = 0;
      const bool stop = split_by_ratio(n, 1.2, [&](std::size_t a, std::size_t b) { return ++asked, g[a][b]; });
      const bool all = split_by_ratio(
          n, 1.2, [&](std::size_t a, std::size_t b) { return ++asked_all, g[a][b]; }, /*every_pair=*/true);
      // Written out: Gmax and Gmin over every pair.
      double gmax = 0, gmin = HUGE_VAL;
      for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = a + 1; b < n; ++b) gmax = std::max(gmax, g[a][b]), gmin = std::min(gmin, g[a][b]);
      const bool want = n >= 2 && gmax > 0 && (gmin == 0 || gmax / gmin > 1.2);
      ASSERT_EQ(all, want) << "n " << n << " trial " << trial;
      ASSERT_EQ(stop, want) << "n " << n << " trial " << trial;
      ASSERT_EQ(asked_all, n < 2 ? 0 : n * (n - 1) / 2);
      early += asked < asked_all;
      splits += want;
      ++trials;
    }
  EXPECT_GT(early, trials / 4);
  EXPECT_GT(splits, trials / 4);
  EXPECT_LT(splits, trials);
}

// The division with every level's kernels gives the scalar level's leaves: through the octree of
// histograms (defaults), through the counting of each examined block (Smin 4: too many bins for
// its voxels; a plugin similarity), with the built-in operator's codes (faces_only) and others.
TEST(Divide, EveryLevelGivesTheLeavesOfTheScalarKernels) {
  std::size_t leaves = 0;
  for (const std::uint64_t seed : {1, 2, 3}) {
    const Grid g = test::random_map(Dims{75 + 20 * seed, 70, 41}, seed, 0.4);
    const TextureMap t = compute_texture(g, 8, 1);
    Params variants[3] = {Params::defaults(), Params::paper(), Params::defaults()};
    variants[1].smin = 4;
    variants[2].similarity = "chi2";
    for (Params& p : variants)
      for (const bool faces_only : {true, false}) {
        const auto* codes = reinterpret_cast<const detail::code_t*>(t.codes.data());
        p.threads = 2;
        const auto want =
            detail::divide_codes(g, codes, t.code_count(), p, faces_only, kernels::table(kernels::Isa::scalar));
        leaves += want.size();
        const int levels = testing_isa::for_each_isa([&](kernels::Isa level) {
          const auto got = detail::divide_codes(g, codes, t.code_count(), p, faces_only, kernels::table(level));
          ASSERT_EQ(got.size(), want.size()) << "seed " << seed << " smin " << p.smin << " " << p.similarity;
          for (std::size_t i = 0; i < got.size(); ++i)
            for (int a = 0; a < 3; ++a) {
              ASSERT_EQ(got[i].lo[a], want[i].lo[a]) << "seed " << seed << " leaf " << i;
              ASSERT_EQ(got[i].hi[a], want[i].hi[a]) << "seed " << seed << " leaf " << i;
            }
        });
        EXPECT_GE(levels, 2);
      }
  }
  EXPECT_GT(leaves, 2000u);  // maps that really split
}
