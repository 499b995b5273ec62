// The default preset's surface band (rules/surface_band.hpp, docs/algorithm.md rule 10): hand-built
// maps where the band just inside a surface must go to the object while the free space in front
// stays free; the rule against a voxel-by-voxel statement of it; thread counts; parameters.
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <random>

#include "isa_levels.hpp"
#include "occseg/error.hpp"
#include "occseg/segment.hpp"
#include "reference/reference.hpp"
#include "rules/surface_band.hpp"

using namespace occseg;

namespace {

// A probability map given by a function of the voxel.
Grid make_map(Dims d, const std::function<float(int, int, int)>& p) {
  Grid g(d, 0.5f, 0.04);
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x) g.p[g.index(x, y, z)] = p(int(x), int(y), int(z));
  return g;
}

State state_at(const Result& r, const Grid& g, int x, int y, int z) {
  return r.segments[r.labels[g.index(std::size_t(x), std::size_t(y), std::size_t(z))]].state;
}

// A wall seen from x < 20 as a range sensor with noise leaves it: free space in front (seen by
// many rays, 0.12), the surface x = 20 (hit, 0.9, but missed here and there: 0.4), the band x = 21
// the overshooting rays crossed (free, 0.4), and the never-observed inside x >= 22 (0.5).
float wall(int x, int y, int z) {
  if (x < 20) return 0.12f;
  if (x == 20) return (y * 7 + z * 3) % 5 == 0 ? 0.4f : 0.9f;
  if (x == 21) return (y + z) % 4 == 0 ? 0.5f : 0.4f;
  return 0.5f;
}

}  // namespace

TEST(SurfaceBand, BandInsideASurfaceGoesToTheObject) {
  const Dims d{40, 32, 24};
  const Grid g = make_map(d, wall);
  const Result r = segment(g, Params());
  Params off;
  off.surface_band = 0;
  const Result without = segment(g, off);
  std::size_t band_free_without = 0;
  for (int z = 0; z < 24; ++z)
    for (int y = 0; y < 32; ++y) {
      if (wall(21, y, z) < 0.45f) {
        EXPECT_EQ(state_at(r, g, 21, y, z), State::occupied) << y << " " << z;
        band_free_without += state_at(without, g, 21, y, z) == State::free;
      }
      for (int x = 0; x < 20; ++x) ASSERT_EQ(state_at(r, g, x, y, z), State::free) << x << " " << y << " " << z;
      EXPECT_EQ(state_at(r, g, 25, y, z), State::unknown);
    }
  EXPECT_GT(band_free_without, 100u);  // without the rule the band is free
  // The wall, its band and its missed surface voxels are one object.
  const std::uint32_t wall_id = r.labels[g.index(20, 1, 1)];
  for (int z = 0; z < 24; ++z)
    for (int y = 0; y < 32; ++y) {
      EXPECT_EQ(r.labels[g.index(20, std::size_t(y), std::size_t(z))], wall_id) << y << " " << z;
      if (wall(21, y, z) < 0.45f) {
        EXPECT_EQ(r.labels[g.index(21, std::size_t(y), std::size_t(z))], wall_id);
      }
    }
}

// Gaps between rays in front of the surface (0.5 voxels touching it, which rule 3 makes unknown)
// put unknown voxels within reach of free voxels in front of it; those are thick free space (a
// 3 x 3 x 3 cube of free voxels holds each) and stay free.
TEST(SurfaceBand, FreeSpaceInFrontOfAPorousSurfaceStaysFree) {
  const Dims d{40, 32, 24};
  const auto porous = [](int x, int y, int z) {
    if (x == 19 && (y % 3 == 0 || z % 4 == 0)) return 0.5f;  // gaps between rays, touching the wall
    if (x == 20 && (y + z) % 6 == 0) return 0.5f;              // holes in the surface
    return wall(x, y, z);
  };
  const Grid g = make_map(d, porous);
  const Result r = segment(g, Params());
  for (int z = 0; z < 24; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 19; ++x) ASSERT_EQ(state_at(r, g, x, y, z), State::free) << x << " " << y << " " << z;
  // The band behind it still goes to the object.
  std::size_t band = 0, taken = 0;
  for (int z = 0; z < 24; ++z)
    for (int y = 0; y < 32; ++y)
      if (porous(21, y, z) < 0.45f) ++band, taken += state_at(r, g, 21, y, z) == State::occupied;
  EXPECT_EQ(taken, band);
}

// The rule's three tests on states alone: a thin free layer between an occupied and an unknown
// one goes; a thin free layer between two occupied ones (free space between two objects) stays;
// thick free space beside both stays.
TEST(SurfaceBand, OnlyThinFreeSpaceNearOccupiedAndUnknownGoes) {
  const Dims d{30, 12, 12};
  std::vector<std::uint8_t> st(d.count(), 0);
  const auto at = [&](int x, int y, int z) { return std::size_t(x) + d.nx * (std::size_t(y) + d.ny * std::size_t(z)); };
  for (int z = 0; z < 12; ++z)
    for (int y = 0; y < 12; ++y) {
      st[at(4, y, z)] = 2;   // surface
      // x = 5: the band (free)
      for (int x = 6; x < 9; ++x) st[at(x, y, z)] = 1;  // inside
      st[at(12, y, z)] = 2;  // object A ...
      // x = 13, 14: free between two objects
      st[at(15, y, z)] = 2;  // ... object B
    }
  std::vector<std::uint8_t> want = st;
  for (int z = 0; z < 12; ++z)
    for (int y = 0; y < 12; ++y) want[at(5, y, z)] = 2;
  // x = 9..11 (three free voxels between unknown and occupied: a 3 x 3 x 3 cube fits) is thick
  // and stays; x = 13, 14 (thin, between two objects) has no unknown voxel within reach and stays.
  Params p;
  std::vector<std::uint8_t> got = st;
  apply_surface_band(got, d, p);
  EXPECT_EQ(got, want);
  // r = 1: x = 5 still has both within one step.
  p.surface_band = 1;
  got = st;
  apply_surface_band(got, d, p);
  EXPECT_EQ(got, want);
  p.surface_band = 0;
  got = st;
  apply_surface_band(got, d, p);
  EXPECT_EQ(got, st);
}

// The bit-mask rule against the voxel-by-voxel statement of it (tests/cpp/reference), on random
// state maps of sizes that cut words and planes in every way, for every radius used.
TEST(SurfaceBand, MatchesAVoxelByVoxelStatement) {
  std::mt19937 rng(7);
  const Dims dims[] = {{1, 1, 1}, {5, 4, 3}, {63, 5, 4}, {64, 3, 5}, {65, 7, 6}, {130, 6, 5}, {40, 30, 1}, {7, 9, 11}};
  for (const Dims& d : dims)
    for (int r : {1, 2, 3})
      for (int density : {2, 6}) {
        std::vector<std::uint8_t> st(d.count());
        for (auto& s : st) {
          const unsigned v = rng() % 16;  // mostly free, so thin and thick free space both occur
          s = v < unsigned(16 - density) ? 0 : (v % 2 ? 1 : 2);
        }
        Params p;
        p.surface_band = r;
        std::vector<std::uint8_t> want = st, got = st;
        reference::apply_surface_band(want, d, p);
        std::vector<std::uint64_t> added;
        apply_surface_band(got.data(), d, p, nullptr, 0, &added);
        ASSERT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " r " << r;
        // The mask of added voxels says which changed.
        const std::size_t W = (d.nx + 63) / 64;
        for (std::size_t i = 0; i < st.size(); ++i) {
          const std::size_t row = i / d.nx, x = i % d.nx;
          const bool bit = (added[row * W + x / 64] >> (x % 64)) & 1u;
          ASSERT_EQ(bit, st[i] != got[i]) << i;
        }
        p.threads = 3;
        std::vector<std::uint64_t> scratch(surface_band_scratch_bytes(d) / 8 + 8);
        testing_isa::for_each_isa([&](kernels::Isa level) {  // the row packing's kernels, every level
          std::vector<std::uint8_t> three = st;
          apply_surface_band(three.data(), d, p, reinterpret_cast<std::uint8_t*>(scratch.data()), scratch.size() * 8,
                             nullptr, kernels::active());
          ASSERT_EQ(three, want) << kernels::isa_name(level);
        });
      }
}

TEST(SurfaceBand, ResultsIdenticalForAnyThreadCount) {
  std::mt19937 rng(3);
  const Dims d{70, 40, 36};
  const Grid g = make_map(d, [&](int x, int y, int z) {
    const float w = wall(x % 35 + 5, y, z);
    return rng() % 10 == 0 ? 0.5f : w;
  });
  Params p;
  p.threads = 1;
  const Result one = segment(g, p);
  for (int t : {2, 3}) {
    p.threads = t;
    const Result r = segment(g, p);
    ASSERT_EQ(r.segments.size(), one.segments.size());
    EXPECT_TRUE(std::equal(r.labels.begin(), r.labels.end(), one.labels.begin())) << t;
  }
}

// A fragment of surface that the band alone lifts over min_object_voxels still joins the object
// beside it as a speckle: rule 7 counts the voxels the map's own evidence made occupied.
TEST(SurfaceBand, BandDoesNotMakeAFragmentAnObject) {
  const Dims d{40, 40, 24};
  // A wall x = 20, y in [4, 20), seen from the front; a strip of surface x = 20, y = 25 (20
  // voxels), 5 unknown voxels farther along (no proximity join), with its band x = 21, y 24..26
  // (60 voxels) before the never-observed inside.
  const auto strip = [](int x, int y, int z) {
    if (z < 2 || z > 21 || x < 20) return 0.12f;
    if (x == 20) return (y >= 4 && y < 20) || y == 25 ? 0.9f : 0.5f;
    if (x == 21 && y >= 24 && y <= 26) return 0.4f;
    return 0.5f;
  };
  const Grid g = make_map(d, strip);
  const Result r = segment(g, Params());
  const std::uint32_t s = r.labels[g.index(20, 25, 10)];
  EXPECT_EQ(r.labels[g.index(21, 24, 10)], s);  // the band went to the strip
  EXPECT_EQ(r.segments[s].state, State::occupied);
  EXPECT_EQ(s, r.labels[g.index(20, 10, 10)]);  // and the strip to the wall
}

TEST(SurfaceBand, ParameterIsSetByNameAndChecked) {
  Params p;
  EXPECT_EQ(get_param(p, "surface_band"), "2");
  set_param(p, "surface_band", "3");
  EXPECT_EQ(p.surface_band, 3);
  EXPECT_THROW(set_param(p, "surface_band", "17"), Error);
  EXPECT_THROW(set_param(p, "surface_band", "-1"), Error);
  EXPECT_THROW(set_param(p, "surface_band", "1.5"), Error);
  EXPECT_EQ(Params::paper().surface_band, 0);
  set_param(p, "preset", "paper");
  EXPECT_EQ(get_param(p, "surface_band"), "0");
}
