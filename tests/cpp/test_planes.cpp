// The support-plane split (occseg/planes.hpp) on hand-built scenes whose answer is known voxel by
// voxel: a floor with things standing on it, a table with legs under it, a lone box, a tilted
// plane.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <functional>
#include <set>

#include "isa_levels.hpp"
#include "occseg/segment.hpp"
#include "rules/objects.hpp"
#include "rules/planes.hpp"
#include "state_scene.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

namespace {

// A map of three states (0 free, 1 unknown, 2 occupied) given by a function of the voxel.
struct Scene : testing_scene::StateScene {
  Scene(Dims d, const std::function<int(int, int, int)>& state) : StateScene(d, 1.0, state) {}
  // Labels as the pipeline's last stage makes them, then the split.
  void label_and_split(std::size_t min_plane, bool conn26 = true) {
    label_components(states, grid, labels, segments, 1, conn26);
    before = segments.size();
    split_support_planes(grid, labels, segments, min_plane, conn26);
  }
  std::size_t before = 0;
};

bool in_box(int x, int y, int z, int x0, int y0, int z0, int x1, int y1, int z1) {
  return x >= x0 && x <= x1 && y >= y0 && y <= y1 && z >= z0 && z <= z1;
}

// A 30 x 30 floor at z = 2 (unknown below, free above) with a 4 x 4 x 5 box on it at z = 3..7.
int floor_with_box(int x, int y, int z) {
  if (z == 2) return 2;
  if (z < 2) return 1;
  return in_box(x, y, z, 10, 12, 3, 13, 15, 7) ? 2 : 0;
}

// Uniform doubles in [0, 1) from a fixed sequence (a 64-bit LCG): the same points everywhere.
class Uniform {
 public:
  explicit Uniform(std::uint64_t seed) : r_(seed) {}
  double operator()() {
    r_ = r_ * 6364136223846793005ull + 1442695040888963407ull;
    return double(r_ >> 11) * 0x1.0p-53;
  }

 private:
  std::uint64_t r_;
};

}  // namespace

TEST(Planes, FitFindsTheDominantPlaneAndCountsItsInliers) {
  std::vector<std::array<double, 3>> pts;
  for (int x = 0; x < 20; ++x)
    for (int y = 0; y < 20; ++y) pts.push_back({double(x), double(y), 5.0});
  for (int k = 0; k < 150; ++k) pts.push_back({double(k % 7), double(k % 11), 6.0 + k % 13});  // off the plane
  Plane pl;
  std::size_t inliers = 0;
  ASSERT_TRUE(fit_dominant_plane(pts, 1, pl, inliers));
  EXPECT_EQ(inliers, 400u);
  EXPECT_NEAR(std::fabs(pl.n[2]), 1.0, 1e-9);
  EXPECT_NEAR(pl.distance(3, 4, 5), 0.0, 1e-9);
  // A digital plane x + 2y + 4z = 60 (centres rounded in z): the least-squares normal is its own.
  pts.clear();
  for (int x = 0; x < 40; ++x)
    for (int y = 0; y < 30; ++y) pts.push_back({double(x), double(y), std::round((60.0 - x - 2.0 * y) / 4.0)});
  ASSERT_TRUE(fit_dominant_plane(pts, 7, pl, inliers));
  EXPECT_EQ(inliers, pts.size());
  const double len = std::sqrt(21.0), sign = pl.n[2] > 0 ? 1 : -1;
  EXPECT_NEAR(sign * pl.n[0], 1 / len, 0.01);
  EXPECT_NEAR(sign * pl.n[1], 2 / len, 0.01);
  EXPECT_NEAR(sign * pl.n[2], 4 / len, 0.01);
  // Degenerate input.
  EXPECT_FALSE(fit_dominant_plane({{0, 0, 0}, {1, 1, 1}}, 1, pl, inliers));
  EXPECT_FALSE(fit_dominant_plane({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}}, 1, pl, inliers));
}

// The cost of a candidate plane, bit for bit: every level's kernels (AVX2: four points at a time)
// against the documented sum written out here, on points with non-integer coordinates (other
// orders of the additions, or of the terms of a distance, round differently) and 1 to 600 of
// them (the vector loop, its tail, the looks at the bound every 256 points).
TEST(Planes, CostIsTheDocumentedSumAtEveryLevel) {
  Uniform uniform(9);
  int differs_from_serial = 0;
  for (std::size_t n : {1, 3, 4, 7, 255, 256, 257, 600}) {
    std::vector<std::array<double, 3>> pts(n);
    for (auto& p : pts) p = {30 * uniform(), 30 * uniform(), 30 * uniform()};
    for (int k = 0; k < 5; ++k) {
      Plane pl;
      const double a = 6.28 * uniform(), b = 3.14 * uniform();
      pl.n = {std::cos(a) * std::sin(b), std::sin(a) * std::sin(b), std::cos(b)};
      pl.d = 15 + 10 * uniform();
      double lane[4] = {0, 0, 0, 0}, serial = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const double e = pl.n[0] * pts[i][0] + pl.n[1] * pts[i][1] + pl.n[2] * pts[i][2] - pl.d;
        const double t = std::min(e * e, kPlaneInlierDistance * kPlaneInlierDistance);
        lane[i % 4] += t;
        serial += t;
      }
      const double want = (lane[0] + lane[1]) + (lane[2] + lane[3]);
      differs_from_serial += want != serial;
      // Scored beside another plane (the search scores draws in pairs): the same bits, or with a
      // bound, a sum at or above it once the cost reaches it.
      Plane other = pl;
      other.d = pl.d - 2.5;
      const double other_cost = detail::msac_cost(pts, other, kernels::table(kernels::Isa::scalar));
      const int levels = for_each_isa([&](kernels::Isa) {
        EXPECT_EQ(detail::msac_cost(pts, pl), want) << n << " points, plane " << k;
        double a = 0, b = 0;
        detail::msac_cost_pair(pts, pl, other, std::numeric_limits<double>::infinity(), a, b);
        EXPECT_EQ(a, want) << n << " points, plane " << k;
        EXPECT_EQ(b, other_cost) << n << " points, plane " << k;
        detail::msac_cost_pair(pts, other, pl, std::numeric_limits<double>::infinity(), b, a);
        EXPECT_EQ(a, want) << n << " points, plane " << k;
        const double stop = 0.5 * (want + other_cost);  // one of them stops early (unless equal)
        detail::msac_cost_pair(pts, pl, other, stop, a, b);
        EXPECT_TRUE(want < stop ? a == want : a >= stop) << n << " points, plane " << k;
        EXPECT_TRUE(other_cost < stop ? b == other_cost : b >= stop) << n << " points, plane " << k;
      });
      EXPECT_GE(levels, 2);
    }
  }
  EXPECT_GT(differs_from_serial, 5);  // the data tell the lanes from one serial sum
}

// The candidate planes are scored in batches over threads, then taken in draw order: the same
// plane, bit for bit, for any thread count, and with every level's cost kernels. Noisy planes
// holding 35 % to 95 % of the points (the adaptive stop then ends anywhere from 13 to all 256
// draws) among uniform outliers, below and above the 4096-point sample, with non-integer
// coordinates (their costs round differently in any other order of additions).
TEST(Planes, FitIsTheSameForAnyThreadCount) {
  Uniform uniform(5);
  int searched = 0;
  for (double share : {0.35, 0.5, 0.7, 0.95})
    for (std::size_t n : {900, 6000}) {
      std::vector<std::array<double, 3>> pts(n);
      for (auto& p : pts) {
        const double x = 40 * uniform(), y = 40 * uniform();
        p = uniform() < share ? std::array<double, 3>{x, y, 0.3 * x - 0.2 * y + 7 + 0.8 * (uniform() - 0.5)}
                              : std::array<double, 3>{x, y, 40 * uniform()};
      }
      Plane one;
      std::size_t in1 = 0;
      ASSERT_TRUE(fit_dominant_plane(pts, 99 + n, one, in1, 1, kernels::table(kernels::Isa::scalar)));
      EXPECT_GT(in1, share * n * 0.8) << share << " " << n;  // it found the plane
      for_each_isa([&](kernels::Isa) {
        for (int t : {1, 2, 3, 0}) {
          Plane pl;
          std::size_t in = 0;
          ASSERT_TRUE(fit_dominant_plane(pts, 99 + n, pl, in, t));
          EXPECT_EQ(pl.n, one.n) << share << " " << n << " threads " << t;
          EXPECT_EQ(pl.d, one.d) << share << " " << n << " threads " << t;
          EXPECT_EQ(in, in1);
        }
      });
      ++searched;
    }
  EXPECT_EQ(searched, 8);
}

// Several candidates: their planes are searched at once on more threads, then split one after
// the other. Three shelves (floors at z = 2, 8, 14 over separate x ranges, unseen below) each
// with a box on it, and a lone box: the same labels and segments for 1, 2 and 3 threads at every
// level of the kernels, and each shelf's box split off.
TEST(Planes, SeveralCandidatesSplitTheSameForAnyThreadCount) {
  auto shelves = [](int x, int y, int z) {
    for (int k = 0; k < 3; ++k) {
      const int x0 = 20 * k, zf = 2 + 6 * k;
      if (x < x0 || x >= x0 + 18) continue;
      if (z < zf) return 1;  // unseen below the shelf: its open side is up
      if (z == zf || in_box(x, y, z, x0 + 6, 6, zf + 1, x0 + 9, 9, zf + 4)) return 2;  // shelf, box
      return 0;
    }
    return in_box(x, y, z, 64, 4, 3, 67, 7, 6) ? 2 : (z < 2 ? 1 : 0);  // a lone box
  };
  const Dims d{70, 18, 20};
  Scene one(d, shelves);
  one.label_and_split(200);
  ASSERT_EQ(one.segments.size(), one.before + 3) << "a box split off each shelf";
  for (int k = 0; k < 3; ++k)
    EXPECT_NE(one.at(20 * k + 7, 7, 3 + 6 * k), one.at(20 * k + 1, 1, 2 + 6 * k)) << "shelf " << k;
  for_each_isa([&](kernels::Isa) {  // every level's costs and box scans
    for (int threads : {1, 2, 3}) {
      Scene s(d, shelves);
      label_components(s.states, s.grid, s.labels, s.segments, 1, true);
      split_support_planes(s.grid, s.labels, s.segments, 200, true, threads);
      EXPECT_EQ(s.labels, one.labels) << threads << " threads";
      ASSERT_EQ(s.segments.size(), one.segments.size());
      for (std::size_t i = 0; i < s.segments.size(); ++i) {
        EXPECT_EQ(s.segments[i].voxels, one.segments[i].voxels) << i;
        EXPECT_EQ(s.segments[i].mop, one.segments[i].mop) << i;
        EXPECT_EQ(s.segments[i].centroid, one.segments[i].centroid) << i;
      }
    }
  });
}

TEST(Planes, BoxStandingOnAFloorBecomesItsOwnSegment) {
  Scene s(Dims{30, 30, 12}, floor_with_box);
  s.label_and_split(256);
  ASSERT_EQ(s.segments.size(), s.before + 1) << "one new segment";
  const std::uint32_t floor_id = s.at(0, 0, 2), box_id = s.at(10, 12, 3);
  EXPECT_EQ(box_id, s.before) << "new segments are numbered after the existing ones";
  EXPECT_EQ(s.ids([](int, int, int z) { return z == 2; }), std::set<std::uint32_t>{floor_id});
  EXPECT_EQ(s.ids([](int x, int y, int z) { return z > 2 && in_box(x, y, z, 10, 12, 3, 13, 15, 7); }),
            std::set<std::uint32_t>{box_id});
  const Segment& f = s.segments[floor_id];
  const Segment& b = s.segments[box_id];
  EXPECT_EQ(f.voxels, 900u);
  EXPECT_EQ(b.voxels, 80u);
  EXPECT_EQ(b.id, box_id);
  EXPECT_EQ(b.state, State::occupied);
  EXPECT_NEAR(b.mop, 0.9, 1e-6);
  EXPECT_EQ(b.bbox_min, (std::array<std::uint32_t, 3>{10, 12, 3}));
  EXPECT_EQ(b.bbox_max, (std::array<std::uint32_t, 3>{13, 15, 7}));
  EXPECT_DOUBLE_EQ(b.centroid[0], 11.5);
  EXPECT_DOUBLE_EQ(b.centroid[2], 5.0);
  EXPECT_EQ(f.bbox_min, (std::array<std::uint32_t, 3>{0, 0, 2}));
  EXPECT_EQ(f.bbox_max, (std::array<std::uint32_t, 3>{29, 29, 2}));
  EXPECT_DOUBLE_EQ(f.centroid[0], 14.5);
  // Other segments are untouched.
  EXPECT_EQ(s.segments[s.at(0, 0, 0)].voxels, 1800u);
}

TEST(Planes, SprawlingSegmentsTakeTheOnePassPathWithTheSameResult) {
  // A one-voxel frame along the 12 edges of the map (a segment whose box is the whole map) next
  // to the floor and box: the candidates' boxes add up to more than the map, so their voxels are
  // bucketed in one pass over the labels instead of scanning each box.
  const auto edge = [](int x, int y, int z) {
    const int ends = (x == 0 || x == 29) + (y == 0 || y == 29) + (z == 0 || z == 11);
    return ends >= 2;
  };
  Scene s(Dims{30, 30, 12}, [&](int x, int y, int z) {
    if (edge(x, y, z)) return 2;
    if (x < 2 || x > 27 || y < 2 || y > 27) return 0;  // free around the floor
    return floor_with_box(x, y, z);
  });
  s.label_and_split(200);  // the frame's 272 voxels make it a candidate too
  ASSERT_EQ(s.segments.size(), s.before + 1);
  const std::uint32_t frame = s.at(0, 0, 0), floor_id = s.at(2, 2, 2), box_id = s.at(10, 12, 3);
  EXPECT_EQ(box_id, s.before);
  EXPECT_NE(floor_id, box_id);
  EXPECT_EQ(s.segments[frame].voxels, 4u * 30 + 4u * 28 + 4u * 10);
  EXPECT_EQ(s.segments[floor_id].voxels, 26u * 26);
  EXPECT_EQ(s.segments[box_id].voxels, 80u);
  EXPECT_EQ(s.ids([](int x, int y, int z) { return z > 2 && in_box(x, y, z, 10, 12, 3, 13, 15, 7); }),
            std::set<std::uint32_t>{box_id});
}

TEST(Planes, FragmentsCutOffByAnObjectJoinIt) {
  // The floor (z = 2) ends at x = 19; a box overhangs its edge (x 18..23), and under the overhang
  // two voxels at floor height touch only the box. Without the box they would be a segment of 2.
  Scene s(Dims{30, 30, 12}, [](int x, int y, int z) {
    if (z == 2 && x <= 19) return 2;
    if (z == 2 && x >= 22 && x <= 23 && y == 13) return 2;
    if (z < 2) return 1;
    return in_box(x, y, z, 18, 12, 3, 23, 15, 7) ? 2 : 0;
  });
  s.label_and_split(256);
  ASSERT_EQ(s.segments.size(), s.before + 1) << "the fragment is no segment of its own";
  const std::uint32_t box_id = s.at(20, 12, 5);
  EXPECT_EQ(s.at(22, 13, 2), box_id);
  EXPECT_EQ(s.at(23, 13, 2), box_id);
  EXPECT_NE(s.at(0, 0, 2), box_id);
  EXPECT_EQ(s.segments[box_id].voxels, 6u * 4 * 5 + 2);
}

// A floor seen in two strips with a line of unknown voxels between them (the rays' gap) is one
// segment by rule 6; a box standing on the first strip splits off, and the far strip, which the
// box never touched, stays with the floor instead of becoming a segment of its own.
TEST(Planes, PartsOfTheSupportTheSplitDidNotCutOffStayWithIt) {
  Scene s(Dims{30, 30, 12}, [](int x, int y, int z) {
    if (z < 2 || (z == 2 && x == 14)) return 1;
    if (z == 2) return 2;
    return in_box(x, y, z, 3, 12, 3, 6, 15, 7) ? 2 : 0;
  });
  label_components(s.states, s.grid, s.labels, s.segments, 1, true);
  ASSERT_NE(s.at(0, 0, 2), s.at(29, 0, 2)) << "the strips are apart before the grouping";
  group_objects(s.grid, s.labels, s.segments, Params::defaults());
  ASSERT_EQ(s.at(0, 0, 2), s.at(29, 0, 2)) << "rule 6 joins the strips across the gap";
  const std::size_t before = s.segments.size();
  split_support_planes(s.grid, s.labels, s.segments, 256, true);
  ASSERT_EQ(s.segments.size(), before + 1) << "the box only";
  const std::uint32_t floor = s.at(0, 0, 2), box = s.at(4, 13, 5);
  EXPECT_NE(box, floor);
  EXPECT_EQ(s.at(29, 29, 2), floor);
  EXPECT_EQ(s.segments[floor].voxels, 29u * 30);
  EXPECT_EQ(s.segments[box].voxels, 4u * 4 * 5);
  EXPECT_EQ(s.segments[floor].bbox_max[0], 29u);
}

TEST(Planes, OffSmallPlanesAndSmallBumpsDoNotSplit) {
  {
    Scene s(Dims{30, 30, 12}, floor_with_box);
    s.label_and_split(0);
    EXPECT_EQ(s.segments.size(), s.before);
    EXPECT_EQ(s.at(0, 0, 2), s.at(10, 12, 3));
  }
  {
    Scene s(Dims{30, 30, 12}, floor_with_box);
    s.label_and_split(901);  // the floor holds 900 voxels
    EXPECT_EQ(s.segments.size(), s.before);
  }
  {
    // A 2 x 2 x 2 bump (8 voxels < kMinObjectVoxels) is noise on the floor.
    Scene s(Dims{30, 30, 12}, [](int x, int y, int z) {
      if (z == 2) return 2;
      if (z < 2) return 1;
      return in_box(x, y, z, 5, 5, 3, 6, 6, 4) ? 2 : 0;
    });
    s.label_and_split(256);
    EXPECT_EQ(s.segments.size(), s.before);
    EXPECT_EQ(s.at(5, 5, 4), s.at(0, 0, 2));
  }
}

// A floor with free space on both sides (a shelf seen from above and below) has no side objects
// stand on: the box on it stays with it.
TEST(Planes, APlaneSeenFromBothSidesDoesNotSplit) {
  Scene s(Dims{30, 30, 14}, [](int x, int y, int z) {
    if (z == 5) return 2;
    return in_box(x, y, z, 10, 12, 6, 13, 15, 10) ? 2 : 0;
  });
  s.label_and_split(256);
  EXPECT_EQ(s.segments.size(), s.before);
  EXPECT_EQ(s.at(10, 12, 6), s.at(0, 0, 5));
  // The same floor seen from above only (unknown below) does let the box go.
  Scene one_side(Dims{30, 30, 14}, [](int x, int y, int z) {
    if (z == 5) return 2;
    if (z < 5) return 1;
    return in_box(x, y, z, 10, 12, 6, 13, 15, 10) ? 2 : 0;
  });
  one_side.label_and_split(256);
  EXPECT_EQ(one_side.segments.size(), one_side.before + 1);
  EXPECT_NE(one_side.at(10, 12, 6), one_side.at(0, 0, 5));
}

TEST(Planes, LegsUnderATableStayWithItsTopAndAMugOnItSplits) {
  // A top at z = 8 (x 2..27, y 2..21) on four 2 x 2 legs (z 0..7); a 3 x 3 x 4 mug on the top.
  // Sensors above: free above and around, the space under the top unknown.
  const auto table = [](int x, int y, int z, bool mug) {
    const bool top = z == 8 && in_box(x, y, z, 2, 2, 8, 27, 21, 8);
    bool leg = false;
    for (int lx : {3, 25})
      for (int ly : {3, 19}) leg = leg || in_box(x, y, z, lx, ly, 0, lx + 1, ly + 1, 7);
    if (top || leg || (mug && in_box(x, y, z, 12, 10, 9, 14, 12, 12))) return 2;
    return (z < 8 && in_box(x, y, z, 2, 2, 0, 27, 21, 7)) ? 1 : 0;
  };
  {
    Scene s(Dims{30, 24, 14}, [&](int x, int y, int z) { return table(x, y, z, false); });
    s.label_and_split(256);
    EXPECT_EQ(s.segments.size(), s.before) << "legs are on the far side of the top";
    EXPECT_EQ(s.at(3, 3, 0), s.at(10, 10, 8));
  }
  Scene s(Dims{30, 24, 14}, [&](int x, int y, int z) { return table(x, y, z, true); });
  s.label_and_split(256);
  ASSERT_EQ(s.segments.size(), s.before + 1);
  const std::uint32_t top = s.at(10, 10, 8), mug = s.at(12, 10, 9);
  EXPECT_NE(top, mug);
  EXPECT_EQ(s.at(3, 3, 0), top);
  EXPECT_EQ(s.at(26, 20, 4), top);
  EXPECT_EQ(s.ids([](int x, int y, int z) { return in_box(x, y, z, 12, 10, 9, 14, 12, 12); }),
            std::set<std::uint32_t>{mug});
  EXPECT_EQ(s.segments[mug].voxels, 36u);
  EXPECT_EQ(s.segments[top].voxels, 26u * 20 + 4 * 4 * 8);
}

TEST(Planes, ABoxOnItsOwnIsNotSplitAtItsTopFace) {
  // A solid 8 x 8 x 8 box in free space: its top face holds 64 of 512 voxels.
  Scene s(Dims{16, 16, 16}, [](int x, int y, int z) { return in_box(x, y, z, 4, 4, 0, 11, 11, 7) ? 2 : 0; });
  s.label_and_split(16);
  EXPECT_EQ(s.segments.size(), s.before);
  // A thin slab seen from both sides (free above and below) has no support side.
  Scene t(Dims{30, 30, 12}, [](int x, int y, int z) {
    return z == 5 || in_box(x, y, z, 10, 10, 6, 13, 13, 9) ? 2 : 0;
  });
  t.label_and_split(256);
  EXPECT_EQ(t.segments.size(), t.before);
}

TEST(Planes, TiltedPlaneAndSixConnectivity) {
  // The digital plane z = round((x + 2y) / 8) + 2 (unknown below, free above) with a 4 x 4 x 6
  // block standing on it; 6-connectivity, so the thick digital plane is still one region.
  const auto ground = [](int x, int y) { return int(std::lround((x + 2.0 * y) / 8.0)) + 2; };
  Scene s(Dims{32, 32, 16}, [&](int x, int y, int z) {
    const int gz = ground(x, y);
    if (z == gz || (z < gz && z >= gz - 1)) return 2;  // two layers: 6-connected across steps
    if (z < gz) return 1;
    return (in_box(x, y, z, 8, 8, 0, 11, 11, 15) && z <= ground(8, 8) + 6) ? 2 : 0;
  });
  s.label_and_split(256, false);
  ASSERT_EQ(s.segments.size(), s.before + 1);
  const std::uint32_t ground_id = s.at(0, 0, ground(0, 0)), block = s.at(9, 9, ground(8, 8) + 5);
  EXPECT_NE(ground_id, block);
  EXPECT_EQ(s.at(31, 31, ground(31, 31)), ground_id);
  EXPECT_EQ(s.segments[block].state, State::occupied);
  EXPECT_GE(s.segments[block].voxels, 4u * 4 * 4);
}

TEST(Planes, PipelineSplitsInTheDefaultPresetOnly) {
  Scene s(Dims{30, 30, 12}, floor_with_box);
  const Result d = segment(s.grid);
  EXPECT_NE(d.labels[s.grid.index(0, 0, 2)], d.labels[s.grid.index(10, 12, 5)]);
  const Result p = segment(s.grid, Params::paper());
  EXPECT_EQ(p.labels[s.grid.index(0, 0, 2)], p.labels[s.grid.index(10, 12, 5)]);
  Params off = Params::defaults();
  off.support_plane = 0;
  const Result o = segment(s.grid, off);
  EXPECT_EQ(o.labels[s.grid.index(0, 0, 2)], o.labels[s.grid.index(10, 12, 5)]);
  // Threads never matter.
  for (int t : {1, 2, 3}) {
    Params q = Params::defaults();
    q.threads = t;
    EXPECT_EQ(segment(s.grid, q).labels, d.labels) << t;
  }
}
