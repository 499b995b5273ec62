// The refinement (section 3.3): the four cases, the scans and the unknown growth.
#include <gtest/gtest.h>

#include "isa_levels.hpp"
#include "random_maps.hpp"
#include "stages/refine.hpp"

using namespace occseg;

namespace {
constexpr std::uint8_t F = 0, U = 1, O = 2;

// A 1 x 1 x n line map: scans along x only see one voxel, so only the z scans act.
Grid line(const std::vector<float>& p) {
  Grid g(Dims{1, 1, p.size()}, 0.5f);
  g.p = p;
  return g;
}
}  // namespace

TEST(Refine, FourCasesFreeToOccupied) {
  Params prm;
  bool re[3];
  const float all_half[3] = {0.5f, 0.5f, 0.5f};
  classify_window(all_half, 3, F, O, prm, re);  // case i
  EXPECT_FALSE(re[0] || re[1] || re[2]);
  const float own[3] = {0.5f, 0.9f, 0.5f};
  classify_window(own, 3, F, O, prm, re);  // case ii
  EXPECT_FALSE(re[0] || re[1] || re[2]);
  const float other[3] = {0.5f, 0.2f, 0.5f};
  classify_window(other, 3, F, O, prm, re);  // case iii: all three move
  EXPECT_TRUE(re[0] && re[1] && re[2]);
  const float mixed[3] = {0.2f, 0.9f, 0.5f};
  classify_window(mixed, 3, F, O, prm, re);  // case iv: <= 0.5 moves
  EXPECT_TRUE(re[0]);
  EXPECT_FALSE(re[1]);
  EXPECT_TRUE(re[2]);
}

TEST(Refine, FourCasesOccupiedToFree) {
  Params prm;
  bool re[3];
  const float own[3] = {0.1f, 0.5f, 0.5f};
  classify_window(own, 3, O, F, prm, re);  // case ii
  EXPECT_FALSE(re[0] || re[1] || re[2]);
  const float other[3] = {0.5f, 0.5f, 0.8f};
  classify_window(other, 3, O, F, prm, re);  // case iii
  EXPECT_TRUE(re[0] && re[1] && re[2]);
  const float mixed[3] = {0.1f, 0.5f, 0.8f};
  classify_window(mixed, 3, O, F, prm, re);  // case iv: >= 0.5 moves
  EXPECT_FALSE(re[0]);
  EXPECT_TRUE(re[1]);
  EXPECT_TRUE(re[2]);
}

TEST(Refine, BoundaryScanMovesThreeVoxels) {
  // Free segment then an occupied segment whose first three voxels are free-valued.
  const Grid g = line({0.2f, 0.2f, 0.2f, 0.3f, 0.5f, 0.9f, 0.9f, 0.9f});
  std::vector<std::uint8_t> st{F, F, F, O, O, O, O, O};
  Params prm;
  prm.refine_passes = 1;
  refine_boundaries(st, g, prm);
  // z+ scan: boundary at 3, window {0.3, 0.5, 0.9} mixed -> 3 and 4 become free.
  EXPECT_EQ(st, (std::vector<std::uint8_t>{F, F, F, F, F, O, O, O}));
}

TEST(Refine, UnknownGrowsOverHalfVoxelsUntilAnotherValue) {
  const Grid g = line({0.5f, 0.5f, 0.5f, 0.5f, 0.3f, 0.5f, 0.2f});
  std::vector<std::uint8_t> st{U, U, F, F, F, F, F};
  refine_unknown(st, g, Params());
  EXPECT_EQ(st, (std::vector<std::uint8_t>{U, U, U, U, F, F, F}));
  // Backward scan: from the other end there is no unknown segment before the free one.
  const Grid h = line({0.2f, 0.5f, 0.5f, 0.5f});
  std::vector<std::uint8_t> s2{F, F, F, U};
  refine_unknown(s2, h, Params());
  EXPECT_EQ(s2, (std::vector<std::uint8_t>{F, U, U, U}));
}

// ---- The scans against the one statement of each rule, at every kernel level ----

namespace {

using occseg::testing_isa::IsaTest;

class RefineScans : public IsaTest {};

// A map holding `lines` lines of `len` voxels along `axis`, line j at the j-th even position of
// the other axis (x for lines along y and z, y for lines along x), a separator line between two
// of them; voxel k of line j is at(j, k).
struct Lines {
  Dims dims;
  int axis;
  Lines(int axis_, std::size_t lines, std::size_t len) : axis(axis_) {
    const std::size_t across = 2 * lines - 1;
    dims = axis == 0 ? Dims{len, across, 1} : (axis == 1 ? Dims{across, len, 1} : Dims{across, 1, len});
  }
  std::size_t index(std::size_t lane, std::size_t k) const {  // lane: position across (2j for line j)
    const std::size_t x = axis == 0 ? k : lane, y = axis == 0 ? lane : (axis == 1 ? k : 0), z = axis == 2 ? k : 0;
    return x + dims.nx * (y + dims.ny * z);
  }
  std::size_t at(std::size_t j, std::size_t k) const { return index(2 * j, k); }
};

const char* axis_name(int axis) { return axis == 0 ? "x" : (axis == 1 ? "y" : "z"); }

// A value on each side of the band, and in it.
float value_of(std::uint8_t own) { return own == F ? 0.2f : (own == O ? 0.9f : 0.5f); }

}  // namespace

// Every window of up to five voxels (each own value below, in or above the band), entered from
// free and from occupied after a run of `from` voxels of 1 to 70 (across the kernels' 16- and
// 32-voxel steps and the 64-voxel words of the own states' bits), along x, y and z, with the
// window as long as the segment or cut by the map's edge: the scans must reassign exactly what
// classify_window() (the four cases' one statement) says. The separators (unknown, at 0.5) and the
// own values before the boundary (on `from`'s side) make every other boundary a case (i) or (ii).
TEST_P(RefineScans, EveryWindowFollowsTheFourCases) {
  Params prm;
  prm.refine_passes = 1;
  int windows = 0, moved = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int len = 1; len <= 5; ++len)
      for (std::uint8_t from : {F, O}) {
        const std::uint8_t into = from == F ? O : F;
        std::size_t combos = 1;
        for (int k = 0; k < len; ++k) combos *= 3;
        for (std::size_t run : {1u, 15u, 16u, 17u, 31u, 33u, 63u, 64u, 70u})
          for (int look : {len, len + 2}) {
            prm.lookahead = look;
            const Lines lines(axis, combos, run + static_cast<std::size_t>(len));
            Grid g(lines.dims, 0.5f);
            std::vector<std::uint8_t> st(lines.dims.count(), U), want;
            for (std::size_t j = 0; j < combos; ++j)
              for (std::size_t k = 0; k < run; ++k) {
                st[lines.at(j, k)] = from;
                g.p[lines.at(j, k)] = value_of(from);
              }
            for (std::size_t j = 0; j < combos; ++j) {
              float p[5];
              std::size_t c = j;
              for (int k = 0; k < len; ++k, c /= 3) {
                p[k] = value_of(static_cast<std::uint8_t>(c % 3));
                g.p[lines.at(j, run + k)] = p[k];
                st[lines.at(j, run + k)] = into;
              }
            }
            want = st;
            for (std::size_t j = 0; j < combos; ++j) {
              float p[5];
              bool re[5];
              for (int k = 0; k < len; ++k) p[k] = g.p[lines.at(j, run + k)];
              classify_window(p, len, from, into, prm, re);
              for (int k = 0; k < len; ++k)
                if (re[k]) {
                  want[lines.at(j, run + k)] = from;
                  ++moved;
                }
              ++windows;
            }
            refine_boundaries(st, g, prm);
            ASSERT_EQ(st, want) << "along " << axis_name(axis) << ", windows of " << len << " entered from "
                                << int(from) << " after " << run << " voxels, look-ahead " << look;
          }
      }
  EXPECT_GT(windows, 10000);
  EXPECT_GT(moved, 10000);
}

// The growth along x (runs of candidates filled at once, grow_up() and grow_down()) against the
// rule as written along z (grow_from(): a candidate after an unknown voxel becomes unknown, lane by
// lane), on the same random lines of 1 to 200 voxels (word ends, runs through several words); the
// separators are occupied, which nothing grows into or from. And along y, also grow_from().
TEST_P(RefineScans, GrowthAlongXIsTheRuleAlongZ) {
  test::Rng r(5);
  int grown = 0;
  for (std::size_t len : {1u, 2u, 63u, 64u, 65u, 127u, 128u, 129u, 200u})
    for (int round = 0; round < 3; ++round) {
      const std::size_t count = 40;
      std::vector<std::vector<float>> p(count, std::vector<float>(len));
      std::vector<std::vector<std::uint8_t>> s(count, std::vector<std::uint8_t>(len));
      for (std::size_t j = 0; j < count; ++j)
        for (std::size_t k = 0; k < len; ++k) {
          const double v = r.uniform(), w = r.uniform();
          p[j][k] = v < 0.6 + 0.1 * round ? 0.5f : (v < 0.9 ? 0.2f : 0.9f);
          s[j][k] = w < 0.8 ? F : (w < 0.9 ? U : O);
        }
      std::vector<std::uint8_t> by_axis[3];
      for (int axis = 0; axis < 3; ++axis) {
        const Lines lines(axis, count, len);
        Grid g(lines.dims, 0.9f);
        std::vector<std::uint8_t> st(lines.dims.count(), O);
        for (std::size_t j = 0; j < count; ++j)
          for (std::size_t k = 0; k < len; ++k) {
            g.p[lines.at(j, k)] = p[j][k];
            st[lines.at(j, k)] = s[j][k];
          }
        refine_unknown(st, g, Params());
        for (std::size_t j = 0; j < count; ++j)
          for (std::size_t k = 0; k < len; ++k) by_axis[axis].push_back(st[lines.at(j, k)]);
      }
      EXPECT_EQ(by_axis[0], by_axis[2]) << "lines of " << len << ", round " << round;
      EXPECT_EQ(by_axis[1], by_axis[2]) << "lines of " << len << ", round " << round;
      for (std::size_t j = 0, i = 0; j < count; ++j)
        for (std::size_t k = 0; k < len; ++k, ++i) grown += s[j][k] == F && by_axis[2][i] == U;
    }
  EXPECT_GT(grown, 1000);
}

OCCSEG_INSTANTIATE_ISA_LEVELS(RefineScans);
