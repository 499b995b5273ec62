// The texture stage (section 2.2): texture units, the contrast quantiser, the codes and their value checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "isa_levels.hpp"
#include "occseg/error.hpp"
#include "stages/texture.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

// The paper's Figure 4, in our neighbour order (x-1, x+1, y-1, y+1, z-1, z+1 = weights 1..32):
// the two neighbours below the centre (2 and 1) sit at weights 1 and 4, the four others
// (8, 7, 7, 6) at 2, 8, 16 and 32.
TEST(Texture, PaperFigure4) {
  const double n[6] = {2, 8, 1, 7, 7, 6};
  const TextureUnit u = texture_unit(5, n);
  EXPECT_EQ(u.lbp, 2 + 8 + 16 + 32);
  EXPECT_DOUBLE_EQ(u.contrast, (8 + 7 + 7 + 6) / 4.0 - (2 + 1) / 2.0);
  EXPECT_DOUBLE_EQ(u.contrast, 5.5);
}

TEST(Texture, EqualNeighbourSetsTheBit) {
  const double n[6] = {0.5, 0.4, 0.6, 0.5, 0.5, 0.5};
  const TextureUnit u = texture_unit(0.5, n);
  EXPECT_EQ(u.lbp, 1 + 4 + 8 + 16 + 32);
  EXPECT_NEAR(u.contrast, (0.5 * 4 + 0.6) / 5 - 0.4, 1e-12);
}

TEST(Texture, OneSidedUnitHasZeroContrast) {
  const double up[6] = {0.9, 0.8, 0.7, 0.6, 0.55, 0.51};
  EXPECT_EQ(texture_unit(0.5, up).lbp, 63);
  EXPECT_EQ(texture_unit(0.5, up).contrast, 0.0);
  const double down[6] = {0.1, 0.2, 0.3, 0.4, 0.45, 0.49};
  EXPECT_EQ(texture_unit(0.5, down).lbp, 0);
  EXPECT_EQ(texture_unit(0.5, down).contrast, 0.0);
}

TEST(Texture, AbsentNeighboursTakeNoPart) {
  const double n[6] = {0.9, 0.1, 0.9, 0.1, 0.0, 1.0};
  const TextureUnit u = texture_unit(0.5, n, 0x0F);  // a 2D map: no z neighbours
  EXPECT_EQ(u.lbp, 1 + 4);
  EXPECT_NEAR(u.contrast, 0.8, 1e-12);
}

TEST(Texture, QuantizerEqualFrequencyWithTies) {
  // 8 levels: level 0 for C = 0, levels 1..7 from the non-zero contrasts.
  std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
  for (int f = 1; f <= 7; ++f) fine[f * 100] = 10;  // seven equally common values
  const ContrastQuantizer q(8, fine);
  EXPECT_EQ(q.level(0.0), 0);
  for (int f = 1; f <= 7; ++f) EXPECT_EQ(q.level((f * 100 + 0.5) / ContrastQuantizer::kFine), f) << f;
  // All mass on one value: every cut sits on it, so it and anything below share level 1, and
  // contrasts never seen above it go to the top level.
  std::vector<std::uint64_t> one(ContrastQuantizer::kFine, 0);
  one[2000] = 1000;
  const ContrastQuantizer q1(8, one);
  EXPECT_EQ(q1.level(2000.5 / ContrastQuantizer::kFine), 1);
  EXPECT_EQ(q1.level(0.01), 1);
  EXPECT_EQ(q1.level(0.99), 7);
}

// The quantiser's lookups by parked step (quantise.hpp) are level(): the table of levels and the
// rises the second pass compares against, for quantisers with tied cuts (all mass on a few
// steps), at the ends of the fine steps (0 and kFine - 1), and for 2 to 64 bins.
TEST(Texture, QuantizerLookupsByParkedStepAreItsLevels) {
  std::uint64_t seed = 3;
  for (int bins : {2, 3, 8, 17, 64})
    for (int spread : {1, 3, 40, ContrastQuantizer::kFine}) {
      std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
      for (int k = 0; k < 300; ++k) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        fine[(seed >> 33) % static_cast<std::uint64_t>(spread) * (ContrastQuantizer::kFine / spread)] += 1 + (seed >> 60);
      }
      fine[ContrastQuantizer::kFine - 1] += 1;
      const ContrastQuantizer q(bins, fine);
      const std::vector<std::uint16_t> level = q.parked_levels(), rises = q.rises();
      ASSERT_EQ(level.size(), static_cast<std::size_t>(ContrastQuantizer::kFine + 1));
      EXPECT_TRUE(std::is_sorted(rises.begin(), rises.end()));
      EXPECT_EQ(rises.size(), static_cast<std::size_t>(level.back() - 1));
      for (int v = 0; v <= ContrastQuantizer::kFine; ++v) {
        const int want = v == 0 ? 0 : q.level_of_step(v - 1);
        ASSERT_EQ(level[v], want) << "bins " << bins << " step " << v;
        int by_rises = v != 0;
        for (std::uint16_t r : rises) by_rises += v > r;
        ASSERT_EQ(by_rises, want) << "bins " << bins << " step " << v;
        const double c = (v - 0.5) / ContrastQuantizer::kFine;  // a contrast of parked step v
        if (v > 0) {
          ASSERT_EQ(ContrastQuantizer::parked_step(c), v);
          ASSERT_EQ(q.level(c), want);
        }
      }
      EXPECT_EQ(ContrastQuantizer::parked_step(0.0), 0);
      EXPECT_EQ(ContrastQuantizer::parked_step(-0.25), 0);
    }
}

// The plugin host's quantisation of a list of contrasts (quantise_contrasts) is the built-in
// operator's: the quantiser of their own fine steps, NaN for no texture.
TEST(Texture, QuantiseContrastsIsTheQuantizersLevel) {
  std::vector<double> c;
  for (int i = 0; i < 500; ++i) c.push_back(i % 7 == 0 ? 0.0 : (i % 11 == 0 ? std::nan("") : (i % 97) / 100.0));
  std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
  for (double v : c)
    if (v > 0) ++fine[ContrastQuantizer::fine_step(v)];
  const ContrastQuantizer q(5, fine);
  std::vector<std::uint16_t> levels(c.size());
  quantise_contrasts(c.data(), c.size(), 5, levels.data(), 0xFFFF);
  for (std::size_t i = 0; i < c.size(); ++i)
    EXPECT_EQ(levels[i], std::isnan(c[i]) ? 0xFFFF : q.level(c[i])) << i;
  EXPECT_THROW(quantise_contrasts(c.data(), c.size(), 1, levels.data(), 0xFFFF), Error);
}

TEST(Texture, CodesSkipBorderVoxels) {
  Grid g(Dims{4, 3, 3}, 0.2f);
  g.at(1, 1, 1) = 0.9f;
  const TextureMap t = compute_texture(g, 8, 1);
  int inner = 0;
  for (std::size_t z = 0; z < 3; ++z)
    for (std::size_t y = 0; y < 3; ++y)
      for (std::size_t x = 0; x < 4; ++x) {
        const bool border = x == 0 || x == 3 || y == 0 || y == 2 || z == 0 || z == 2;
        EXPECT_EQ(t.codes[g.index(x, y, z)] == kNoTexture, border);
        inner += !border;
      }
  EXPECT_EQ(inner, 2);
  // (1,1,1) is the peak: no neighbour >= 0.9, LBP 0, contrast 0 -> code 0.
  EXPECT_EQ(t.codes[g.index(1, 1, 1)], 0);
  // (2,1,1): neighbour x-1 = 0.9 and the five others at 0.2 are all >= 0.2: LBP 63, C = 0.
  EXPECT_EQ(t.codes[g.index(2, 1, 1)], 63 * 8 + 0);
}

TEST(Texture, TwoDimensionalMapKeepsInPlaneTexture) {
  Grid g(Dims{3, 3, 1}, 0.2f);
  g.at(2, 1, 0) = 0.8f;
  g.at(1, 0, 0) = 0.1f;
  const TextureMap t = compute_texture(g, 4, 1);
  // Only (1,1,0) is interior: x-1 = 0.2, x+1 = 0.8, y+1 = 0.2 are >= 0.2, y-1 = 0.1 is below:
  // LBP 1+2+8, C = 0.4 - 0.1 = 0.3 > 0.
  const std::uint16_t c = t.codes[g.index(1, 1, 0)];
  EXPECT_EQ(c / 4, 11);
  EXPECT_EQ(c % 4, 1);  // the only non-zero contrast in the map: level 1
}

// compute_texture() checks the values itself (segment() relies on it for the built-in operator):
// one bad value anywhere - a face, the interior, the first or last plane, a chunk boundary for
// 1-3 threads - is an Error(bad_value) naming that voxel, as check_probabilities() words it.
// Every kind of place a bad value can sit: the outer faces (rows the kernels never see as
// centres), and inside rows of 19 interior voxels, in the vector kernels' groups of 8 (and 16)
// and in their scalar tails; for each kernel the processor has, since each checks its own rows.
TEST(Texture, BadValuesAreErrorsNamingTheVoxel) {
  const Dims d{21, 7, 6};
  const float bad[] = {std::nanf(""), INFINITY, -0.25f, 1.5f, std::nextafter(1.0f, 2.0f), -1e-40f};
  const std::size_t spots[][3] = {{0, 0, 0}, {4, 3, 2}, {20, 6, 5}, {0, 3, 3}, {5, 0, 4},  {2, 6, 1},
                                  {1, 1, 1}, {12, 3, 2}, {16, 4, 4}, {17, 2, 3}, {19, 5, 1}, {20, 2, 4}};
  constexpr int kSpots = sizeof spots / sizeof spots[0];
  int checked = 0;
  const int levels = for_each_isa([&](kernels::Isa level) {
    for (float v : bad)
      for (const auto& s : spots)
        for (int threads : {1, 2, 3}) {
          Grid g(d, 0.3f);
          for (std::size_t i = 0; i < g.p.size(); ++i) g.p[i] = 0.1f + 0.8f * float(i % 5) / 4;
          g.p[g.index(s[0], s[1], s[2])] = v;
          const std::string where = "voxel (" + std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " +
                                    std::to_string(s[2]) + ")";
          try {
            compute_texture(g, 8, threads);
            ADD_FAILURE() << "no error for " << v << " at " << where << ", threads " << threads << ", kernels "
                          << kernels::isa_name(level);
          } catch (const Error& e) {
            EXPECT_EQ(e.status(), Status::bad_value);
            EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
            ++checked;
          }
        }
  });
  EXPECT_EQ(checked, levels * 6 * kSpots * 3);
}

// The edges of [0, 1] are valid wherever they sit, -0.0 (which compares equal to 0) and
// subnormals included; every kernel accepts them and gives the same codes. (The AVX-512 kernel
// tests a row's values as unsigned bit patterns, where -0.0 lies above 1.0: such rows take the
// exact test.)
TEST(Texture, EdgeValuesAreAccepted) {
  const Dims d{37, 6, 5};
  Grid g(d, 0.3f);
  const float edge[] = {-0.0f, 0.0f, 1.0f, 1e-40f, std::nextafter(1.0f, 0.0f)};
  for (std::size_t i = 0; i < g.p.size(); ++i) g.p[i] = i % 3 ? 0.1f + 0.8f * float(i % 7) / 6 : edge[i % 5];
  std::vector<std::uint16_t> first;
  for_each_isa([&](kernels::Isa level) {
    for (int threads : {1, 2}) {
      const TextureMap t = compute_texture(g, 8, threads);
      if (first.empty()) first = t.codes;
      EXPECT_EQ(t.codes, first) << "kernels " << kernels::isa_name(level) << " threads " << threads;
    }
  });
  EXPECT_EQ(std::count(first.begin(), first.end(), kNoTexture), 2 * (37 * 6 + 37 * 5 + 6 * 5) - 4 * (37 + 6 + 5) + 8);
}
