// The segment creation (section 3.2): block means, states, own states and the fused map pass.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>

#include "isa_levels.hpp"
#include "occseg/registry.hpp"
#include "pipeline/map_pass.hpp"
#include "random_maps.hpp"
#include "stages/codes.hpp"
#include "stages/create.hpp"
#include "stages/own_states.hpp"
#include "stages/refine.hpp"
#include "stages/texture.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

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
    const UninitVector<std::uint8_t> st = detail::create_segments_and_own_states(g, blocks, p, own.data());
    const std::vector<std::uint8_t> plain = create_segments(g, blocks, p);
    EXPECT_TRUE(std::equal(st.begin(), st.end(), plain.begin(), plain.end())) << "map " << k;
    ASSERT_EQ(own.size(), g.p.size());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < own.size(); ++i) wrong += own[i] != static_cast<std::uint8_t>(p.state_of(g.p[i]));
    EXPECT_EQ(wrong, 0u) << "map " << k;
    EXPECT_EQ(own, own_states(g, p)) << "map " << k;
  }
}

// The block means are summed in mean_occupancy()'s order (cell by cell over 8^3 cells, each
// cell's voxels in scan order, the cells in scan order), whether creation reads the map row by
// row (blocks that tile it on the cell lattice, as division's leaves do) or block by block (any
// other disjoint blocks). With t = 2^-54 (a quarter of 1.0's ulp u = 2^-52), 1.0 + t rounds back
// to 1.0 while k t added before the 1.0 round to a multiple of u, so the sums below differ with
// the order, and thresholds on exactly the documented sums tell it from the others.
TEST(Create, BlockMeansAddCellByCellOnBothPaths) {
  const float t = std::ldexp(1.0f, -54);
  const double u = std::ldexp(1.0, -52);
  Grid g(Dims{24, 16, 16}, 0.0f);
  // Block A (16^3, eight cells): 1.0 first in its first cell, 2t in the cell at (0, 8, 0) and
  // 4t = u in the one at (8, 8, 0). In order: 1 + 0.5u ties back to 1.0, then 1 + u. The whole
  // block in scan order instead: 1.0 (each t after the 1.0 rounds away); the cells of a row in
  // the other order: 1 + u, then 1 + 1.5u ties to 1 + 2u.
  g.at(0, 0, 0) = 1.0f;
  g.at(1, 10, 3) = g.at(2, 10, 3) = t;
  for (std::uint32_t x = 9; x < 13; ++x) g.at(x, 10, 3) = t;
  // Block B (8^3, one cell): 1.0 as its second voxel, t everywhere else. In scan order the first
  // t and the 1.0 make 1.0, and every t after rounds away: exactly 1.0. A row read backwards puts
  // 6 t first: 1 + 2u.
  for (std::uint32_t z = 0; z < 8; ++z)
    for (std::uint32_t y = 0; y < 8; ++y)
      for (std::uint32_t x = 16; x < 24; ++x) g.at(x, y, z) = t;
  g.at(17, 0, 0) = 1.0f;
  const Block a{{0, 0, 0}, {16, 16, 16}}, b{{16, 0, 0}, {24, 8, 8}};
  std::vector<Block> tiling = {a, b, {{16, 8, 0}, {24, 16, 8}}, {{16, 0, 8}, {24, 8, 16}}, {{16, 8, 8}, {24, 16, 16}}};
  // The same blocks with the last one cut at x = 18: off the cell lattice, read block by block.
  std::vector<Block> cut = tiling;
  cut.back().hi[0] = 18;
  cut.push_back({{18, 8, 8}, {24, 16, 16}});
  EXPECT_EQ(mean_occupancy(g, a), (1 + u) / 4096);
  EXPECT_EQ(mean_occupancy(g, b), 1.0 / 512);
  for (const auto& blocks : {tiling, cut}) {
    Params p;
    p.free_below = 1e-30;        // blocks of zeros: free
    p.occupied_above = 1.0 / 4096;  // A just above the bound: occupied; the whole block in scan order: not
    std::vector<std::uint8_t> st = create_segments(g, blocks, p);
    EXPECT_EQ(st[g.index(5, 9, 3)], 2) << blocks.size() << " blocks";
    EXPECT_EQ(st[g.index(20, 12, 12)], 0);
    p.occupied_above = (1 + u) / 4096;  // A exactly at the bound: unknown; the cells in another order: not
    st = create_segments(g, blocks, p);
    EXPECT_EQ(st[g.index(5, 9, 3)], 1) << blocks.size() << " blocks";
    p.occupied_above = 1.0 / 512;  // B exactly at the bound: unknown; any other order: occupied
    st = create_segments(g, blocks, p);
    EXPECT_EQ(st[g.index(20, 2, 2)], 1) << blocks.size() << " blocks";
    for (int threads : {1, 2, 3}) {
      p.threads = threads;
      EXPECT_EQ(create_segments(g, blocks, p), st) << threads << " threads";
    }
  }
}

// Creation's row-by-row sums (the AVX2 path adds eight cells of a row at once) against
// mean_occupancy(), bit for bit. Each 8^3 cell starts with 1.0 and holds half-ulps of 1.0 (2^-53,
// slightly more, a quarter, zero) elsewhere: each addition then rounds to even or not depending
// on what came before, so the same values in another order, even two neighbours swapped, give
// another sum in most cells (checked below), and a voxel added out of turn, to the wrong cell or
// twice shows. Rows of 9, 16 and 17 cells: whole groups of eight and scalar leftovers.
TEST(Create, RowSumsAreMeanOccupancyBitForBit) {
  const Dims dims[] = {{72, 16, 12}, {130, 17, 20}, {128, 8, 8}};
  for (std::size_t k = 0; k < 3; ++k) {
    Grid g(dims[k], 0.0f);
    test::Rng r(70 + k);
    const float half = std::ldexp(1.0f, -53);
    const float values[4] = {half, half * (1.0f + std::ldexp(1.0f, -7)), half / 2, 0.0f};
    for (float& v : g.p) v = values[r.below(4)];
    for (std::uint32_t z = 0; z < g.dims.nz; z += 8)
      for (std::uint32_t y = 0; y < g.dims.ny; y += 8)
        for (std::uint32_t x = 0; x < g.dims.nx; x += 8) g.at(x, y, z) = 1.0f;
    // 16^3 blocks where they fit whole, 8^3 cells (clipped by the far faces) elsewhere.
    const auto fits16 = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
      return x + 16 <= g.dims.nx && y + 16 <= g.dims.ny && z + 16 <= g.dims.nz;
    };
    std::vector<Block> blocks;
    for (std::uint32_t z = 0; z < g.dims.nz; z += 8)
      for (std::uint32_t y = 0; y < g.dims.ny; y += 8)
        for (std::uint32_t x = 0; x < g.dims.nx; x += 8) {
          const std::uint32_t ax = x / 16 * 16, ay = y / 16 * 16, az = z / 16 * 16;
          if (fits16(ax, ay, az)) {
            if (x == ax && y == ay && z == az) blocks.push_back({{x, y, z}, {x + 16, y + 16, z + 16}});
            continue;
          }
          blocks.push_back({{x, y, z},
                            {std::min<std::uint32_t>(x + 8, g.dims.nx), std::min<std::uint32_t>(y + 8, g.dims.ny),
                             std::min<std::uint32_t>(z + 8, g.dims.nz)}});
        }
    std::size_t reordered_differs = 0;
    for (const Block& b : blocks) {
      Grid swapped = g;  // voxels 4 and 5 of every row swapped
      for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
        for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
          for (std::uint32_t x = b.lo[0]; x + 8 <= b.hi[0]; x += 8) std::swap(swapped.at(x + 4, y, z), swapped.at(x + 5, y, z));
      reordered_differs += mean_occupancy(swapped, b) != mean_occupancy(g, b);
    }
    ASSERT_GT(reordered_differs, blocks.size() / 3) << "map " << k << ": the values do not tell orders apart";
    // Every level of the row kernels the processor has, on 1 to 3 threads.
    for_each_isa([&](kernels::Isa) {
      for (int threads : {1, 2, 3}) {
        const std::vector<double> means = detail::block_means_by_rows(g, blocks, threads);
        ASSERT_EQ(means.size(), blocks.size()) << "map " << k << ": the blocks do not tile it";
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < blocks.size(); ++i) wrong += means[i] != mean_occupancy(g, blocks[i]);
        EXPECT_EQ(wrong, 0u) << "map " << k << ", " << threads << " threads";
      }
    });
  }
}

// Division's leaves on maps whose sides are not multiples of Smin (cells clipped by the far
// faces), Smin 4 and 8: every voxel gets the state of its block's mean, and voxels outside every
// block stay free when the blocks do not tile the map.
TEST(Create, EveryVoxelGetsItsBlocksState) {
  const Dims dims[] = {{37, 29, 21}, {70, 9, 33}, {8, 64, 3}};
  for (std::size_t k = 0; k < 3; ++k) {
    const Grid g = test::random_map(dims[k], 60 + k, 0.5);
    Params p;
    p.smin = k == 1 ? 4 : 8;
    p.threads = 2;
    std::vector<Block> blocks = divide(g, compute_texture(g, p.contrast_bins, p.threads), p);
    for (bool whole : {true, false}) {
      if (!whole) blocks.erase(blocks.begin() + static_cast<std::ptrdiff_t>(blocks.size() / 2));
      std::vector<std::uint8_t> expect(g.p.size(), 0);
      for (const Block& b : blocks) {
        const auto s = static_cast<std::uint8_t>(p.state_of(mean_occupancy(g, b)));
        for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
          for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
            for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) expect[g.index(x, y, z)] = s;
      }
      EXPECT_EQ(create_segments(g, blocks, p), expect) << "map " << k << (whole ? "" : ", a block missing");
    }
  }
}

// segment()'s fused map pass has the texture's first pass hand the map's rows to the creation
// (own states and cell sums) while it reads them: on any thread count and kernels the result must
// be creation's own, bit for bit, and the codes the texture's. Values that tell orders apart (as
// above: 1 at each cell's first voxel, then values of 2^-53 whose sum depends on the order), map
// depths that are not multiples of the cells' 8 planes (the texture's per-thread groups must
// start on a cell), and a band that leaves all three own states; the own states both as bytes and
// as bits (the pipeline's).
TEST(Create, FusedMapPassAddsTheRowsAsCreationDoes) {
  const Dims dims[] = {{37, 29, 23}, {70, 9, 41}, {16, 16, 16}, {9, 3, 30}};
  const TextureOperator* lbp6 = find_texture("lbp6");
  ASSERT_NE(lbp6, nullptr);
  ASSERT_NE(lbp6->native_into, nullptr);
  for (std::size_t k = 0; k < 4; ++k) {
    Grid g(dims[k], 0.0f);
    test::Rng r(90 + k);
    const float half = std::ldexp(1.0f, -53);
    const float values[6] = {half, half * (1.0f + std::ldexp(1.0f, -7)), half / 2, 0.0f, 0.5f, 0.9f};
    for (float& v : g.p) v = values[r.below(6)];
    for (std::uint32_t z = 0; z < g.dims.nz; z += 8)
      for (std::uint32_t y = 0; y < g.dims.ny; y += 8)
        for (std::uint32_t x = 0; x < g.dims.nx; x += 8) g.at(x, y, z) = 1.0f;
    float lo = 0, hi = 0;
    detail::float_bounds(Params().free_below, Params().occupied_above, lo, hi);
    std::vector<std::uint8_t> want_own(g.p.size(), 0xEE);
    detail::CellRows want(g, want_own.data(), lo, hi, nullptr, nullptr, kernels::table(kernels::Isa::scalar).create);
    for (std::size_t z = 0; z < g.dims.nz; ++z)
      for (std::size_t y = 0; y < g.dims.ny; ++y) want.add_row(y, z, g.values() + g.index(0, y, z));
    ASSERT_EQ(want_own, own_states(g, Params())) << "map " << k;
    const detail::OwnBitsStore want_bits = detail::pack_own_bits(want_own.data(), g.dims, 1);
    const TextureMap want_codes = compute_texture(g, 8, 1);
    for_each_isa([&](kernels::Isa) {
      for (int threads : {1, 2, 3, 5})
        for (bool as_bits : {false, true}) {
          const std::string what = "map " + std::to_string(k) + ", " + std::to_string(threads) + " threads, own states as " +
                                   (as_bits ? "bits" : "bytes");
          std::vector<std::uint8_t> own(g.p.size(), 0xEE), lbp(g.p.size());
          std::vector<std::uint64_t> u(want_bits.unknown.size(), ~0ull), o(want_bits.occupied.size(), ~0ull);
          std::vector<std::uint16_t> codes(g.p.size());
          detail::CellRows rows = as_bits ? detail::CellRows(g, nullptr, lo, hi, u.data(), o.data())
                                          : detail::CellRows(g, own.data(), lo, hi);
          Params p;
          p.threads = threads;
          EXPECT_EQ(detail::fused_map_pass(*lbp6, g, p, kernels::active(), codes.data(), lbp.data(), rows), 64 * 8);
          EXPECT_EQ(codes, want_codes.codes) << what;
          if (as_bits) {
            EXPECT_EQ(u, want_bits.unknown) << what;
            EXPECT_EQ(o, want_bits.occupied) << what;
          } else {
            EXPECT_EQ(own, want_own) << what;
          }
          ASSERT_EQ(rows.sums().size(), want.sums().size());
          std::size_t wrong = 0;
          for (std::size_t i = 0; i < rows.sums().size(); ++i) wrong += rows.sums()[i] != want.sums()[i];
          EXPECT_EQ(wrong, 0u) << what;
        }
    });
  }
}
