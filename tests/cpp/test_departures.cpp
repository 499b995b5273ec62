#include <gtest/gtest.h>

#include <algorithm>

#include "rules/departures.hpp"

using namespace occseg;

TEST(Departures, ThinGapsAreNotUnknownRegions) {
  Grid g(Dims{20, 20, 20}, 0.2f);
  // A 1-voxel-thick sheet of 0.5 (a gap between rays) and a 4x4x4 unknown cube.
  for (int z = 0; z < 20; ++z)
    for (int y = 0; y < 20; ++y) g.at(3, y, z) = 0.5f;
  for (int z = 10; z < 14; ++z)
    for (int y = 10; y < 14; ++y)
      for (int x = 10; x < 14; ++x) g.at(x, y, z) = 0.5f;
  const auto m = unknown_regions(g, Params());
  EXPECT_EQ(m[g.index(3, 5, 5)], 0);
  for (int z = 10; z < 14; ++z)
    for (int y = 10; y < 14; ++y)
      for (int x = 10; x < 14; ++x) EXPECT_EQ(m[g.index(x, y, z)], 1);
  EXPECT_EQ(m[g.index(9, 10, 10)], 0);
  EXPECT_EQ(m[g.index(14, 13, 13)], 0);
}

TEST(Departures, RegionAtTheMapEdgeSurvives) {
  Grid g(Dims{10, 10, 10}, 0.2f);
  for (int z = 0; z < 10; ++z)
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 2; ++x) g.at(x, y, z) = 0.5f;  // 2 thick, cut by the edge
  const auto m = unknown_regions(g, Params());
  EXPECT_EQ(m[g.index(0, 0, 0)], 1);
  EXPECT_EQ(m[g.index(1, 9, 9)], 1);
  EXPECT_EQ(m[g.index(2, 5, 5)], 0);
}

// The bit-mask opening against its definition, computed voxel by voxel: a 0.5 voxel is in a
// region when some cube of edge 2r + 1 around a centre within r of it (centre inside the map)
// holds only 0.5 voxels, the outside counting as 0.5. Rows of 1, 63, 64, 65 and 130 voxels
// (word boundaries of the bit rows), radii 1-3, random masks of several densities, 1 to 5 threads
// (each takes a stretch of planes and computes the planes around it again: deeper maps too).
TEST(Departures, UnknownRegionsMatchTheirDefinition) {
  std::uint64_t seed = 12345;
  auto next = [&] {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<unsigned>(seed >> 33);
  };
  const Dims shapes[] = {{1, 9, 7}, {63, 5, 6}, {64, 4, 7}, {65, 7, 3}, {130, 3, 5}, {70, 1, 1}, {20, 4, 23}, {9, 3, 31}};
  for (const Dims& d : shapes)
    for (int r = 1; r <= 3; ++r)
      for (unsigned density : {50u, 85u, 97u}) {
        Grid g(d, 0.2f);
        for (float& v : g.p) v = next() % 100 < density ? 0.5f : 0.2f;
        Params prm;
        prm.gap_radius = r;
        std::vector<std::vector<std::uint8_t>> by_threads;
        for (int t : {1, 2, 3, 5}) {
          prm.threads = t;
          by_threads.push_back(unknown_regions(g, prm));
        }
        const auto& m = by_threads[1];
        for (std::size_t k = 0; k < by_threads.size(); ++k) EXPECT_EQ(by_threads[k], m) << "thread counts " << k;
        const long nx = long(d.nx), ny = long(d.ny), nz = long(d.nz);
        auto half = [&](long x, long y, long z) {
          if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) return true;
          return g.at(std::size_t(x), std::size_t(y), std::size_t(z)) == 0.5f;
        };
        auto cube = [&](long cx, long cy, long cz) {
          for (long z = cz - r; z <= cz + r; ++z)
            for (long y = cy - r; y <= cy + r; ++y)
              for (long x = cx - r; x <= cx + r; ++x)
                if (!half(x, y, z)) return false;
          return true;
        };
        std::size_t wrong = 0, in = 0;
        for (long z = 0; z < nz; ++z)
          for (long y = 0; y < ny; ++y)
            for (long x = 0; x < nx; ++x) {
              bool want = false;
              if (half(x, y, z))
                for (long cz = std::max(0L, z - r); cz <= std::min(nz - 1, z + r) && !want; ++cz)
                  for (long cy = std::max(0L, y - r); cy <= std::min(ny - 1, y + r) && !want; ++cy)
                    for (long cx = std::max(0L, x - r); cx <= std::min(nx - 1, x + r) && !want; ++cx)
                      want = cube(cx, cy, cz);
              in += want;
              wrong += m[g.index(std::size_t(x), std::size_t(y), std::size_t(z))] != (want ? 1 : 0);
            }
        EXPECT_EQ(wrong, 0u) << d.nx << "x" << d.ny << "x" << d.nz << " r " << r << " density " << density;
        if (density == 97u && r == 1) {
          EXPECT_GT(in, 0u) << "the test must see regions";
        }
      }
}

TEST(Departures, VoxelRules) {
  Grid g(Dims{5, 1, 1}, 0.2f);
  g.p = {0.9f, 0.5f, 0.2f, 0.5f, 0.2f};
  Params prm;
  // Texture says free everywhere; the occupied voxel stays occupied, the gap next to it becomes
  // unknown, the free-surrounded gap stays free.
  std::vector<std::uint8_t> st(5, 0);
  apply_voxel_rules(st, g, prm);
  EXPECT_EQ(st, (std::vector<std::uint8_t>{2, 1, 0, 0, 0}));
  // Texture says occupied: a free-valued voxel is free, a gap keeps the texture's state.
  std::vector<std::uint8_t> so(5, 2);
  apply_voxel_rules(so, g, prm);
  EXPECT_EQ(so, (std::vector<std::uint8_t>{2, 2, 0, 2, 0}));
}

TEST(Departures, GapConnectedToAnObjectIsNeverFree) {
  // A table top seen only edge-on: a 2-voxel-thick slab of 0.5 (too thin to be an unknown region)
  // with free space above and below and an occupied rim at x = 2. Texture says free everywhere.
  Grid g(Dims{30, 12, 12}, 0.2f);
  for (int z = 5; z < 7; ++z)
    for (int y = 0; y < 12; ++y) {
      g.at(2, y, z) = 0.9f;
      for (int x = 3; x < 28; ++x) g.at(x, y, z) = 0.5f;
    }
  // A separate ray gap in free space, touching nothing occupied.
  for (int y = 0; y < 12; ++y) g.at(15, y, 10) = 0.5f;
  std::vector<std::uint8_t> st(g.p.size(), 0);
  apply_voxel_rules(st, g, Params());
  for (int y = 0; y < 12; ++y) {
    EXPECT_EQ(st[g.index(3, y, 5)], 1) << "touches the rim";
    EXPECT_EQ(st[g.index(27, y, 6)], 1) << "25 voxels from the rim, same gap";
    EXPECT_EQ(st[g.index(15, y, 10)], 0) << "a gap between rays stays free";
  }
}

// A floor (z = 0) of occupied voxels under a 2-voxel layer of 0.5 (ray gaps: thinner than the
// 3-voxel cube of gap_radius 1) in free space, and a sheet of 0.5 (x = 20, 21) standing on that
// layer up to the top of the map: its gap is connected to the floor only through the bottom
// planes, so the flood climbs through every plane (and, on more threads, through every slab of
// planes: the floor's 5,120 seeds take that path). A sheet touching nothing (x = 40, 41) stays
// free. The same states on 1 to 4 threads.
TEST(Departures, GapFloodOnThreadsClimbsThroughEveryPlane) {
  Grid g(Dims{64, 80, 48}, 0.1f);
  for (std::size_t z = 0; z < 48; ++z)
    for (std::size_t y = 0; y < 80; ++y)
      for (std::size_t x = 0; x < 64; ++x) {
        float& v = g.at(x, y, z);
        if (z == 0)
          v = 0.9f;
        else if (z <= 2 || x == 20 || x == 21 || ((x == 40 || x == 41) && y >= 10 && y <= 50 && z >= 10 && z <= 40))
          v = 0.5f;
      }
  std::vector<std::uint8_t> want;
  for (int threads : {1, 2, 3, 4}) {
    Params p;
    p.threads = threads;
    std::vector<std::uint8_t> st(g.p.size(), 0);
    apply_voxel_rules(st, g, p);
    if (threads == 1) {
      want = st;
      EXPECT_EQ(st[g.index(20, 40, 47)], 1) << "the top of the standing sheet";
      EXPECT_EQ(st[g.index(21, 79, 3)], 1);
      EXPECT_EQ(st[g.index(10, 30, 2)], 1) << "the floor's layer";
      EXPECT_EQ(st[g.index(40, 30, 30)], 0) << "the sheet touching nothing";
      EXPECT_EQ(st[g.index(10, 30, 30)], 0) << "free space";
      EXPECT_EQ(st[g.index(10, 30, 0)], 2);
    } else {
      EXPECT_EQ(st, want) << threads << " threads";
    }
  }
}
